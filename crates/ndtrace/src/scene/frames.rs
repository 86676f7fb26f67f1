//! Frame reuse: the scene of an animation frame made from the scene of the frame before
//! without building it again, bit for bit what a build gives. A frame that moves the camera
//! shares the objects and the index ([`Scene::with_camera`]); a frame that moves objects
//! shares the trees that hold large objects in their own space and reaches them through the
//! new transforms ([`Scene::moved`]).

use super::build::{check_composite, extent_of, parts, world_boxes, Parts, Scene};
use super::camera::build_camera;
use super::desc::{CameraDesc, ObjectDesc, SceneDesc};
use super::fields::R;
use super::objects::hints;
use crate::accel::{rebuild_members, AccelObject, AccelOptions, ToObject, MORTON_MIN};
use std::sync::Arc;

impl<const N: usize> Scene<N> {
    /// This scene seen by the camera `camera` (with the `[composite]` options `composite`
    /// checked against its retina): what building the description with that camera gives,
    /// bit for bit — nothing of a build but the camera and that check depends on the camera —
    /// sharing the objects and the BVH instead of building them again (animation frames that
    /// move only the camera).
    pub fn with_camera(
        &self,
        camera: &CameraDesc,
        composite: Option<&crate::composite::CompositeOptions>,
    ) -> R<Scene<N>> {
        let camera = build_camera::<N>(camera)?;
        check_composite(composite, &camera)?;
        Ok(Scene {
            camera,
            ..self.clone()
        })
    }

    /// The scene `desc` describes, when `desc` differs from the description this scene was
    /// built from only in its camera, `[composite]` and objects' transforms (a frame of an
    /// animation that moves objects; the caller makes sure of that: the objects' meshes must
    /// be the same): its objects are built as a build makes them, and this scene's trees are
    /// reached through the new transforms ([`crate::accel::Instances::moved`]) instead of
    /// being built: the large objects' trees hold them in their own space, so nothing per
    /// simplex is done for them; the objects traced in world space get a tree built anew when
    /// one of them moves. It traces bit for bit as a build of `desc`. `None` when an object is
    /// read from a file (it would be read again), a large object's transform turns handedness
    /// around where this scene's did not or the reverse (the simplices' order would differ), or
    /// the number of degenerate simplices changed (the warnings would): build `desc` then. Its
    /// warnings are this scene's (orientation and degeneracy do not depend on the transforms).
    pub(crate) fn moved(&self, desc: &SceneDesc) -> Option<R<Scene<N>>> {
        // Clips and caps (which depend on the objects' places) are made by a build.
        if desc.objects.iter().any(ObjectDesc::reads_file) || self.clips.active() {
            return None;
        }
        let options = AccelOptions {
            shadows: desc.render.shadows && !desc.lights.is_empty(),
            morton_min: MORTON_MIN,
            instance_min: self.instance_min,
        };
        let Parts {
            background,
            ambient,
            camera,
            lights,
            mut objects,
            maps,
            ..
        } = match parts::<N>(desc, None, None, (&options, false)) {
            Ok(p) => p,
            Err(e) => return Some(Err(e)),
        };
        let offsets = crate::accel::offsets_of(objects.iter().map(|o| &o.mesh)).0;
        if offsets != self.offsets || objects.len() != self.objects.len() {
            return None;
        }
        // Objects held in their own space have the simplices' order of the transform's
        // handedness: it must be the same.
        let counts: Vec<usize> = objects.iter().map(|o| o.mesh.simplices.len()).collect();
        let flip = |m: Option<&ToObject<N>>| m.is_some_and(|m| m.flip);
        let same_order = (0..maps.len())
            .filter(|&k| options.own_space(counts[k]))
            .all(|k| flip(maps[k].as_ref()) == flip(self.instances.map(k)));
        if !same_order {
            return None;
        }
        // Smaller ones are held in world space: when one moves, they get a tree of their own,
        // built over the moved vertices as a build of `desc` prepares them.
        let small: Vec<usize> = (0..maps.len())
            .filter(|&k| counts[k] > 0 && !options.own_space(counts[k]))
            .collect();
        let moved: Vec<usize> = (small.iter().copied())
            .filter(|&k| objects[k].mesh != self.objects[k].mesh)
            .collect();
        // The certificates: an object held in its own space keeps its own (found there, as a
        // build of `desc` finds it), and so does an unmoved one (maybe found already, by a
        // trace of this scene); a moved one held in world space gets one to find anew.
        for (k, (o, base)) in objects.iter_mut().zip(self.objects.iter()).enumerate() {
            o.convex = match moved.contains(&k) {
                true => hints(desc.objects[k].shape).certificate(&options, None, None),
                false => base.convex.clone(),
            };
        }
        let boxes = world_boxes(&objects);
        let (objects, instances) = if moved.is_empty() {
            (Arc::new(objects), self.instances.moved(maps, &boxes))
        } else {
            let rebuilt = {
                let mut index: Vec<AccelObject<'_, N>> = (objects.iter_mut().zip(&desc.objects))
                    .map(|(o, d)| AccelObject {
                        mesh: &mut o.mesh,
                        own: None,
                        map: None,
                        hints: hints(d.shape),
                    })
                    .collect();
                rebuild_members(&self.instances, &mut index, &offsets, &small, &options)
            };
            // A simplex that became degenerate or the reverse changes the warnings: build.
            if rebuilt.skipped() != self.skipped_degenerate {
                return None;
            }
            // The moved objects in world space, as this frame's objects hold them.
            let objects = Arc::new(objects);
            let instances = rebuilt.finish(&self.instances, &objects, (maps, &boxes));
            (objects, instances)
        };
        let extent = extent_of(&objects, &offsets, instances.slots());
        let edge_cache = Arc::new(
            self.edge_cache
                .moved(|o| objects[o].mesh == self.objects[o].mesh),
        );
        Some(Ok(Scene {
            camera,
            objects,
            lights,
            ambient,
            background,
            render: desc.render.clone(),
            instances,
            offsets,
            skipped_degenerate: self.skipped_degenerate,
            extent,
            warnings: self.warnings.clone(),
            edge_cache,
            instance_min: self.instance_min,
            clips: self.clips.clone(),
        }))
    }
}

#[cfg(test)]
mod tests;
