//! The cache of a scene's feature edges ([`EdgeCache`]): what the mesh data of its objects
//! gives once, kept for the frames and views that share the objects.

use super::features::Ridges;
use crate::linalg::Vector;
use crate::NdResult;
use std::collections::HashMap;
use std::sync::{Arc, Mutex};

/// The feature edges of a built scene's objects by crease angle, found once (they depend on the
/// geometry, not on the camera) and shared by the scenes [`crate::scene::Scene::with_camera`] makes, so that
/// the frames of a camera animation do not look for them again; and the objects' [`Ridges`],
/// shared by the frames of an animation that moves objects (`EdgeCache::moved`), so that a
/// moved object's edges come from its ridges and its new normals instead of a search from
/// scratch. The ridges of an object take about 10·N bytes per simplex, kept while a scene
/// sharing them lives.
#[derive(Debug, Default)]
pub struct EdgeCache<const N: usize> {
    edges: Mutex<HashMap<EdgeKey, Arc<Vec<[u32; 2]>>>>,
    ridges: Arc<Mutex<HashMap<usize, Arc<Ridges<N>>>>>,
}

/// An [`EdgeCache`] entry's key: the object's index and the bits of the crease angle.
type EdgeKey = (usize, u64);

impl<const N: usize> EdgeCache<N> {
    /// The feature edges of object `object`, the mesh `(vertices, simplices)`, at
    /// `angle_degrees`: cached, or found from the object's ridges (cached when they
    /// [fit](Ridges::fits) the mesh, else found and cached).
    pub(crate) fn feature_edges(
        &self,
        object: usize,
        angle_degrees: f64,
        vertices: &[Vector<N>],
        simplices: &[[u32; N]],
    ) -> NdResult<Arc<Vec<[u32; 2]>>> {
        let key = (object, angle_degrees.to_bits());
        if let Some(e) = self.edges.lock().map_err(|_| poisoned())?.get(&key) {
            return Ok(Arc::clone(e));
        }
        let ridges = self.ridges(object, vertices, simplices)?;
        let edges = Arc::new(ridges.feature_edges(vertices, angle_degrees)?);
        self.edges
            .lock()
            .map_err(|_| poisoned())?
            .insert(key, Arc::clone(&edges));
        Ok(edges)
    }

    /// The [`Ridges`] of object `object`, the mesh `(vertices, simplices)`: cached when they
    /// [fit](Ridges::fits) the mesh, else found and cached.
    pub(crate) fn ridges(
        &self,
        object: usize,
        vertices: &[Vector<N>],
        simplices: &[[u32; N]],
    ) -> NdResult<Arc<Ridges<N>>> {
        let known = self
            .ridges
            .lock()
            .map_err(|_| poisoned())?
            .get(&object)
            .cloned();
        Ok(match known {
            Some(r) if r.fits(vertices, simplices) => r,
            _ => {
                let r = Arc::new(Ridges::new(vertices, simplices)?);
                self.ridges
                    .lock()
                    .map_err(|_| poisoned())?
                    .insert(object, Arc::clone(&r));
                r
            }
        })
    }

    /// The cache of a scene whose objects are this scene's, moved ([`crate::scene::Scene`]'s
    /// frames that move objects): the feature edges of the objects `unmoved` says are unchanged (same vertices
    /// and simplices) are kept, and the ridges are shared, each checked against its object's
    /// mesh when used.
    pub(crate) fn moved(&self, unmoved: impl Fn(usize) -> bool) -> Self {
        let edges = match self.edges.lock() {
            Ok(e) => e
                .iter()
                .filter(|((o, _), _)| unmoved(*o))
                .map(|(k, v)| (*k, Arc::clone(v)))
                .collect(),
            Err(_) => HashMap::new(),
        };
        EdgeCache {
            edges: Mutex::new(edges),
            ridges: Arc::clone(&self.ridges),
        }
    }
}

#[cfg(test)]
impl<const N: usize> EdgeCache<N> {
    /// The objects with cached feature edges, and each object's cached ridges (by address).
    pub(crate) fn contents(&self) -> (Vec<usize>, Vec<(usize, usize)>) {
        let mut edges: Vec<usize> = self.edges.lock().unwrap().keys().map(|k| k.0).collect();
        edges.sort_unstable();
        let mut ridges: Vec<(usize, usize)> = (self.ridges.lock().unwrap().iter())
            .map(|(o, r)| (*o, Arc::as_ptr(r) as usize))
            .collect();
        ridges.sort_unstable();
        (edges, ridges)
    }
}

fn poisoned() -> crate::NdError {
    crate::NdError::Value {
        arg: "scene".into(),
        message: "the feature-edge cache was poisoned by an earlier panic".into(),
    }
}
