//! Feature edges: the 1-dimensional edges of a mesh's polytope structure.
//!
//! A mesh tessellates an (N−1)-manifold into (N−1)-simplices, but the *polytope* it describes
//! has coarser faces: a tesseract's boundary is 48 tetrahedra, its structure 8 cubes, 24
//! squares, 32 edges. Hollasch's and the course's wireframe pictures draw those 32 edges, not
//! the 120 edges of the tetrahedra. This module recovers them from the simplices alone:
//!
//! 1. **Creases** (faces of dimension N−2, the ridges): a ridge is a crease if two simplices
//!    sharing it have unit normals (eq. 6) more than `angle` apart — comparing the normals'
//!    *lines*, |n̂_a · n̂_b| < cos(angle), so the orientation of the input does not matter — or
//!    if only one simplex has it (a boundary of an open mesh).
//! 2. **Down the face dimensions**: a face of dimension m < N−2 is a feature face if the feature
//!    faces of dimension m+1 containing it do not all lie in one (m+1)-flat. Two (m+1)-faces
//!    through an m-face G lie in one flat exactly when their directions away from G (the part
//!    of the opposite vertex orthogonal to G's affine span) are parallel or opposite, so again
//!    lines are compared with the same `angle`.
//! 3. The feature faces of dimension 1 are the feature edges. For N = 3 the creases are the
//!    edges themselves; for N = 2 every non-degenerate segment is an edge.
//!
//! Input that real tools produce is handled: vertices with bit-identical coordinates are welded
//! first (a mesh written face by face), and zero-volume simplices (Qhull's triangulated facets
//! contain some, to keep a conforming triangulation where two neighbouring facets were split
//! differently) glue their ridges together: every simplex that shares any ridge with a
//! zero-volume simplex becomes a neighbour of the others across it, so the zero-volume simplex
//! neither hides a crease nor invents a boundary.
//!
//! Most of the work — welding and sorting every ridge incidence — depends only on which
//! vertices the simplices share, not on where the vertices are: [`Ridges`] keeps it, so that a
//! mesh that moves (an animation's frames) finds its edges again from its new normals alone.

use super::find;
use crate::linalg::{dot, norm, scale, sub, Vector};
use crate::par;
use crate::NdResult;
use rayon::prelude::*;
use std::collections::HashMap;

/// Fewest items of a parallel loop's range (the items here are cheap).
///
/// The loops go through [`crate::par`], not rayon pipelines: this code is compiled once per
/// dimension N, and a pipeline would instantiate rayon's machinery for each of its closures.
/// The sorts keep `par_sort_unstable` on element types that do not depend on N (one
/// instantiation for all N).
const PAR_MIN: usize = 256;

/// Largest number of vertices of a face key (a ridge of an 8-D mesh has 7).
const KEY: usize = 8;
/// A face as its sorted vertex ids, padded with `u32::MAX`.
type Key = [u32; KEY];
/// Relative volume below which a simplex counts as having none (looser than the tracer's
/// tolerance: the zero-volume simplices of a Qhull triangulation come out of floating-point
/// arithmetic with relative volumes around 1e-15 … 1e-10).
pub const FLAT_TOLERANCE: f64 = 1e-9;

/// The feature edges of the mesh `(vertices, simplices)` (every simplex N vertex ids), as
/// sorted, deduplicated vertex pairs `[i, j]` with i < j (ids refer to `vertices`; of vertices
/// welded for having the same coordinates, the smallest id is used). See the module docs for
/// the definition; `angle_degrees` is the crease angle (in [0, 90]).
pub fn feature_edges<const N: usize>(
    vertices: &[Vector<N>],
    simplices: &[[u32; N]],
    angle_degrees: f64,
) -> NdResult<Vec<[u32; 2]>> {
    check_angle(angle_degrees)?;
    Ridges::new(vertices, simplices)?.feature_edges(vertices, angle_degrees)
}

fn check_angle(angle_degrees: f64) -> NdResult<()> {
    if (0.0..=90.0).contains(&angle_degrees) {
        return Ok(());
    }
    Err(crate::NdError::Value {
        arg: "angle".into(),
        message: format!("must be in [0, 90] degrees, got {angle_degrees}"),
    })
}

/// The part of [`feature_edges`] that depends only on which vertices the simplices share: the
/// welded simplices and every ridge with the simplices around it. It is most of the work (a
/// sort of all N·S ridge incidences), and it does not change while a mesh moves, so the frames
/// of an animation that turns an object find their feature edges from it again
/// ([`Ridges::fits`]), with the normals of the moved vertices: the same edges as a search from
/// scratch, bit for bit, because the welding is checked and every decision that depends on
/// coordinates is made again.
#[derive(Debug)]
pub struct Ridges<const N: usize> {
    /// Per vertex, the smallest id of a vertex with the same coordinates.
    weld: Vec<u32>,
    /// The simplices with welded ids.
    simplices: Vec<[u32; N]>,
    /// Every (ridge of N − 1 distinct vertices, simplex) incidence as `simplex·N + corner left
    /// out`, grouped by ridge (groups in the order of their sorted vertex ids, each by simplex).
    incidences: Vec<u32>,
    /// Where each ridge's group starts in `incidences`, and the end.
    starts: Vec<u32>,
}

impl<const N: usize> Ridges<N> {
    /// The ridges of `(vertices, simplices)` (errors name a simplex with an id out of range, a
    /// vertex that is not finite, or a mesh too large to number its incidences in 32 bits).
    pub fn new(vertices: &[Vector<N>], simplices: &[[u32; N]]) -> NdResult<Self> {
        for (s, simplex) in simplices.iter().enumerate() {
            if let Some(&bad) = simplex.iter().find(|&&v| v as usize >= vertices.len()) {
                return Err(crate::NdError::Value {
                    arg: "simplices".into(),
                    message: format!(
                        "simplex {s} names vertex {bad}, but there are {} vertices",
                        vertices.len()
                    ),
                });
            }
        }
        if simplices.len() > u32::MAX as usize / N {
            return Err(crate::NdError::Value {
                arg: "simplices".into(),
                message: format!(
                    "{} simplices: feature edges are found for at most {} in {N}D",
                    simplices.len(),
                    u32::MAX as usize / N
                ),
            });
        }
        check_finite(vertices)?;
        let weld = weld(vertices);
        let simplices = welded(&weld, simplices);
        if N == 2 {
            return Ok(Ridges {
                weld,
                simplices,
                incidences: Vec::new(),
                starts: vec![0],
            });
        }
        // Every (ridge, simplex) incidence, grouped by ridge.
        let mut inc: Vec<(Key, u32)> = par::flat_collect(simplices.len(), PAR_MIN, |r, out| {
            for s in r {
                let simplex = &simplices[s];
                out.extend((0..N).filter_map(|skip| {
                    let k = key_of((0..N).filter(|&j| j != skip).map(|j| simplex[j]));
                    distinct(&k, N - 1).then_some((k, (s * N + skip) as u32))
                }));
            }
        });
        inc.par_sort_unstable();
        let mut starts = Vec::new();
        for (i, w) in inc.iter().enumerate() {
            if i == 0 || inc[i - 1].0 != w.0 {
                starts.push(i as u32);
            }
        }
        starts.push(inc.len() as u32);
        Ok(Ridges {
            weld,
            simplices,
            incidences: inc.into_iter().map(|(_, i)| i).collect(),
            starts,
        })
    }

    /// Whether these are the ridges of `(vertices, simplices)` too: the vertices weld alike and
    /// the welded simplices are the same (true for a mesh moved by any map that keeps its
    /// distinct vertices distinct, such as a rotation).
    pub fn fits(&self, vertices: &[Vector<N>], simplices: &[[u32; N]]) -> bool {
        vertices.len() == self.weld.len()
            && simplices.len() == self.simplices.len()
            && weld(vertices) == self.weld
            && par::reduce_ranges(
                simplices.len(),
                PAR_MIN,
                true,
                |mut r| {
                    r.all(|i| {
                        let (s, w) = (&simplices[i], &self.simplices[i]);
                        (0..N).all(|k| self.weld.get(s[k] as usize) == Some(&w[k]))
                    })
                },
                |a, b| a && b,
            )
    }

    /// The feature edges of the mesh with these ridges and the coordinates `vertices` (see
    /// [`feature_edges`]; the caller makes sure the ridges [`fit`](Self::fits)).
    pub fn feature_edges(
        &self,
        vertices: &[Vector<N>],
        angle_degrees: f64,
    ) -> NdResult<Vec<[u32; 2]>> {
        check_angle(angle_degrees)?;
        check_finite(vertices)?;
        let cos_angle = angle_degrees.to_radians().cos();
        if N == 2 {
            let mut out: Vec<[u32; 2]> = self
                .simplices
                .iter()
                .filter(|s| s[0] != s[1])
                .map(|s| [s[0].min(s[1]), s[0].max(s[1])])
                .collect();
            out.sort_unstable();
            out.dedup();
            return Ok(out);
        }
        let normals: Vec<Option<Vector<N>>> =
            par::map_collect(self.simplices.len(), PAR_MIN, |i| {
                let s = &self.simplices[i];
                let pts: [Vector<N>; N] = std::array::from_fn(|k| vertices[s[k] as usize]);
                unit_normal(&pts)
            });
        let mut faces = self.creases(&normals, cos_angle);
        // Down the face dimensions: faces of `m + 1` vertices from those of `m + 2`.
        for m in (2..N - 1).rev() {
            faces = lower_features(vertices, &faces, m, cos_angle);
        }
        let mut out: Vec<[u32; 2]> = faces.iter().map(|k| [k[0], k[1]]).collect();
        out.sort_unstable();
        out.dedup();
        Ok(out)
    }

    /// The number of ridges.
    pub fn ridge_count(&self) -> usize {
        self.starts.len() - 1
    }

    /// The incidences of ridge `r`: `simplex·N + corner left out` for each simplex that has
    /// it (the ridge is that simplex's other N − 1 vertices).
    pub fn group(&self, r: usize) -> &[u32] {
        &self.incidences[self.starts[r] as usize..self.starts[r + 1] as usize]
    }

    /// Simplex `s` with its vertices welded (of vertices with the same coordinates, the
    /// smallest id stands for all).
    pub fn welded(&self, s: usize) -> &[u32; N] {
        &self.simplices[s]
    }

    /// The sorted vertex ids of ridge `r`.
    fn key(&self, r: usize) -> Key {
        let i = self.incidences[self.starts[r] as usize] as usize;
        let (simplex, skip) = (&self.simplices[i / N], i % N);
        key_of((0..N).filter(|&j| j != skip).map(|j| simplex[j]))
    }

    /// Step 1: the crease ridges (keys of N−1 vertices).
    fn creases(&self, normals: &[Option<Vector<N>>], cos_angle: f64) -> Vec<Key> {
        let normal = |i: u32| normals[i as usize / N];
        // Whether simplices (with volume) around one ridge or glued class meet at a crease:
        // `owners` are simplex ids times `per` (plus less than `per`).
        let crease = |owners: &[u32], per: u32| {
            let normal = |a: u32| normals[(a / per) as usize].unwrap();
            owners.len() < 2
                || owners.iter().enumerate().any(|(i, &a)| {
                    let na = normal(a);
                    owners[i + 1..]
                        .iter()
                        .any(|&b| dot(&na, &normal(b)).abs() < cos_angle)
                })
        };
        if normals.iter().all(Option::is_some) {
            // Nothing glued: a ridge's owners are its group's simplices (a simplex with volume
            // has distinct vertices, so it has each ridge once).
            return par::flat_collect(self.ridge_count(), PAR_MIN, |r, out| {
                out.extend(
                    r.filter(|&r| crease(self.group(r), N as u32))
                        .map(|r| self.key(r)),
                );
            });
        }
        // Zero-volume simplices glue their ridges into one class.
        let mut parent: Vec<u32> = (0..self.ridge_count() as u32).collect();
        let mut first_ridge: HashMap<u32, u32> = HashMap::new();
        for r in 0..self.ridge_count() {
            for &i in self.group(r) {
                if normal(i).is_none() {
                    let s = i / N as u32;
                    match first_ridge.get(&s) {
                        None => {
                            first_ridge.insert(s, r as u32);
                        }
                        Some(&r0) => {
                            let (a, b) = (find(&mut parent, r0), find(&mut parent, r as u32));
                            parent[a.max(b) as usize] = a.min(b);
                        }
                    }
                }
            }
        }
        // The simplices with volume around each class.
        let mut owners: Vec<(u32, u32)> = Vec::with_capacity(self.incidences.len());
        for r in 0..self.ridge_count() {
            let class = find(&mut parent, r as u32);
            for &i in self.group(r) {
                if normal(i).is_some() {
                    owners.push((class, i / N as u32));
                }
            }
        }
        owners.par_sort_unstable();
        owners.dedup();
        let mut is_crease = vec![false; self.ridge_count()];
        let mut has_owner = vec![false; self.ridge_count()];
        for group in owners.chunk_by(|a, b| a.0 == b.0) {
            let class = group[0].0 as usize;
            has_owner[class] = true;
            let ids: Vec<u32> = group.iter().map(|&(_, s)| s).collect();
            is_crease[class] = crease(&ids, 1);
        }
        (0..self.ridge_count())
            .filter(|&r| {
                let class = find(&mut parent, r as u32) as usize;
                has_owner[class] && is_crease[class]
            })
            .map(|r| self.key(r))
            .collect()
    }
}

fn check_finite<const N: usize>(vertices: &[Vector<N>]) -> NdResult<()> {
    match vertices
        .iter()
        .position(|v| v.iter().any(|x| !x.is_finite()))
    {
        None => Ok(()),
        Some(v) => Err(crate::NdError::Value {
            arg: "vertices".into(),
            message: format!("vertex {v} is not finite: {:?}", vertices[v]),
        }),
    }
}

/// `simplices` with every id replaced by its welded one.
fn welded<const N: usize>(weld: &[u32], simplices: &[[u32; N]]) -> Vec<[u32; N]> {
    simplices
        .iter()
        .map(|s| std::array::from_fn(|k| weld[s[k] as usize]))
        .collect()
}

/// For each vertex, the smallest id of a vertex with the same coordinates (−0 = +0).
fn weld<const N: usize>(vertices: &[Vector<N>]) -> Vec<u32> {
    let mut first: HashMap<[u64; N], u32> = HashMap::with_capacity(vertices.len());
    vertices
        .iter()
        .enumerate()
        .map(|(i, v)| {
            let bits: [u64; N] = std::array::from_fn(|k| (v[k] + 0.0).to_bits());
            *first.entry(bits).or_insert(i as u32)
        })
        .collect()
}

/// The unit normal (direction of eq. 6) of an (N−1)-simplex, or `None` when its relative
/// volume `|cross(unit edges)|` is at most [`FLAT_TOLERANCE`] (repeated ids included).
fn unit_normal<const N: usize>(points: &[Vector<N>; N]) -> Option<Vector<N>> {
    let mut edges = [[0.0; N]; N];
    for k in 1..N {
        let e = sub(&points[k], &points[0]);
        let l = norm(&e);
        if !(l > 0.0) {
            return None;
        }
        edges[k - 1] = scale(&e, 1.0 / l);
    }
    let n = crate::geometry::generalized_cross(&edges[..N - 1]);
    let l = norm(&n);
    (l > FLAT_TOLERANCE).then(|| scale(&n, 1.0 / l))
}

/// `ids` sorted into a padded key (its first `ids.len()` slots).
fn key_of(ids: impl Iterator<Item = u32>) -> Key {
    let mut k = [u32::MAX; KEY];
    for (slot, id) in ids.enumerate() {
        k[slot] = id;
    }
    k.sort_unstable();
    k
}

/// Whether a key of `len` vertices names `len` distinct vertices.
fn distinct(k: &Key, len: usize) -> bool {
    k[..len].windows(2).all(|w| w[0] != w[1])
}

/// Step 2: the feature faces of `m` vertices, given those of `m + 1` vertices.
fn lower_features<const N: usize>(
    vertices: &[Vector<N>],
    faces: &[Key],
    m: usize,
    cos_angle: f64,
) -> Vec<Key> {
    // Every (face, direction away from it) of the faces above, grouped by face.
    let inc: Vec<(Key, Vector<N>)> = par::flat_collect(faces.len(), PAR_MIN, |r, out| {
        for f in &faces[r] {
            out.extend((0..=m).filter_map(|skip| {
                let g = key_of((0..=m).filter(|&j| j != skip).map(|j| f[j]));
                away(vertices, &g[..m], f[skip]).map(|d| (g, d))
            }));
        }
    });
    // Grouped by face through (face, index) pairs, whose type does not depend on N (see
    // [`PAR_MIN`]); a group's test below does not depend on the order of its members, and
    // the faces come out sorted, as a sort of `inc` by face would give them.
    let mut order: Vec<(Key, usize)> = (inc.iter().enumerate())
        .map(|(i, (g, _))| (*g, i))
        .collect();
    order.par_sort_unstable();
    let away_of = |i: usize| &inc[i].1;
    order
        .chunk_by(|a, b| a.0 == b.0)
        .filter(|group| {
            group.iter().enumerate().any(|(i, a)| {
                group[i + 1..]
                    .iter()
                    .any(|b| dot(away_of(a.1), away_of(b.1)).abs() < cos_angle)
            })
        })
        .map(|group| group[0].0)
        .collect()
}

/// The unit direction from the affine span of `face` toward `apex` (orthogonal to the span),
/// or `None` if the apex lies on the span (within [`FLAT_TOLERANCE`] of its distance scale).
fn away<const N: usize>(vertices: &[Vector<N>], face: &[u32], apex: u32) -> Option<Vector<N>> {
    let o = vertices[face[0] as usize];
    let mut d = sub(&vertices[apex as usize], &o);
    let scale_len = norm(&d);
    // Gram–Schmidt over the face's edges (twice, for accuracy).
    let mut basis: Vec<Vector<N>> = Vec::with_capacity(face.len());
    for &v in &face[1..] {
        let mut e = sub(&vertices[v as usize], &o);
        for _ in 0..2 {
            for b in &basis {
                let c = dot(&e, b);
                e = crate::linalg::add_scaled(&e, -c, b);
            }
        }
        let l = norm(&e);
        if !(l > FLAT_TOLERANCE * norm(&sub(&vertices[v as usize], &o))) {
            return None;
        }
        basis.push(scale(&e, 1.0 / l));
    }
    for _ in 0..2 {
        for b in &basis {
            let c = dot(&d, b);
            d = crate::linalg::add_scaled(&d, -c, b);
        }
    }
    let l = norm(&d);
    (l > FLAT_TOLERANCE * scale_len).then(|| scale(&d, 1.0 / l))
}

#[cfg(test)]
mod tests;
