//! Clip hyperplanes: rays ignore the hits on the far side of an object's clip hyperplanes
//! (course notes, "Clipping Tests in N Dimensions": the side of a point is the sign of
//! n̂·x − c, eq. 1), so that a closed object can be cut open; caps fill the cut.
//!
//! The index knows nothing of clips: a ray's nearest hit is found as without them, and only when
//! the scene has clips is it checked here. A hit on the far side of one of its object's
//! hyperplanes, n̂·x > c at x = o + t·d, is rejected, and the ray is traced again without that
//! simplex (a flat simplex meets a ray at most once), until a hit is kept or none is left. The
//! result is the least (t, id) over the kept hits, as a brute-force test of every simplex
//! would give it, whatever the thread count. A scene without clips does none of this: one
//! branch per group of rays ([`crate::scene::clip::Clips::active`]).
//!
//! A cap (`cap = true`) is an extra object of simplices filling the object's cut in the clip
//! hyperplane (`scene/clip.rs`, from `crate::mesh::slice`). A convex object's cut is convex
//! and its cap is exact. For any other closed mesh a hit on the cap counts only where the cap
//! lies inside the object: where the object's next hit along the ray (clipped or not) leaves
//! it, n̂_s·d > 0 for an outward mesh.
//!
//! Shadow rays respect clips the same way: a light is blocked by a kept hit before it.

use crate::linalg::dot;
use crate::ray::{Hit, Ray};
use crate::scene::Scene;
use std::ops::Range;

/// Most hits a ray may reject before it is counted as a miss (a safeguard; a ray through an
/// ordinary clipped scene rejects a few).
pub const MAX_REJECTED: usize = 4096;

/// Whether `hit` of `ray` is kept by the clips of its object.
#[inline]
fn keeps<const N: usize>(scene: &Scene<N>, ray: &Ray<N>, hit: &Hit<N>) -> bool {
    let (obj, _) = scene.locate(hit.prim);
    let c = &scene.clips.objects[obj];
    let x = ray.at(hit.t);
    if !c.keeps_point(&x) {
        return false;
    }
    match &c.inside_of {
        None => true,
        Some(ids) => {
            // Inside the capped object: its next hit along the ray leaves it.
            let next = scene
                .instances
                .closest_hit(ray, hit.t, f64::INFINITY, &|id| ids.contains(&id));
            next.is_some_and(|h| dot(&h.normal, &ray.dir) > 0.0)
        }
    }
}

/// The nearest hit of `ray` in (tmin, tmax) among the simplices `accept` passes that its
/// object's clips keep, given `first`, the nearest hit without clips.
pub fn nearest_kept<const N: usize>(
    scene: &Scene<N>,
    ray: &Ray<N>,
    tmin: f64,
    tmax: f64,
    accept: &dyn Fn(u32) -> bool,
    first: Option<Hit<N>>,
) -> Option<Hit<N>> {
    let mut hit = first?;
    let mut rejected: Vec<u32> = Vec::new();
    loop {
        if keeps(scene, ray, &hit) {
            return Some(hit);
        }
        if rejected.len() >= MAX_REJECTED {
            return None;
        }
        rejected.push(hit.prim);
        hit = scene
            .instances
            .closest_hit(ray, tmin, tmax, &|id| accept(id) && !rejected.contains(&id))?;
    }
}

/// Whether a kept hit blocks the shadow ray `ray` in (0, tmax), skipping the ids `skip`.
pub fn blocks<const N: usize>(
    scene: &Scene<N>,
    ray: &Ray<N>,
    tmax: f64,
    skip: &Range<u32>,
) -> bool {
    let first = scene
        .instances
        .closest_hit(ray, 0.0, tmax, &|id| !skip.contains(&id));
    nearest_kept(scene, ray, 0.0, tmax, &|id| !skip.contains(&id), first).is_some()
}

/// [`nearest_kept`] for each of a packet's camera rays, in place: `hits` are their nearest hits
/// among the simplices `accept` passes, without clips.
pub(crate) fn clip_hits<const N: usize>(
    scene: &Scene<N>,
    rays: &[Ray<N>],
    accept: &impl Fn(u32) -> bool,
    hits: &mut [Option<Hit<N>>],
) {
    for (ray, hit) in rays.iter().zip(hits.iter_mut()) {
        if hit.is_some() {
            *hit = nearest_kept(scene, ray, 0.0, f64::INFINITY, accept, *hit);
        }
    }
}
