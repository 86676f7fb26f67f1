//! Hyperplane slices: the intersection of an (N−1)-simplex mesh in R^N with the hyperplane
//! n̂·x = offset, as an (N−2)-simplex mesh in the hyperplane's own orthonormal coordinates
//! (course notes, "Clipping Tests in N Dimensions": which side from the signed volume, eq. 1,
//! and where an edge crosses, eq. 10).
//!
//! Each simplex is cut on its own, in four steps:
//!
//! 1. The side of each vertex, d_i = n̂·x_i − offset (eq. 1; the sign of V_N(x) of eq. 3 for
//!    the hyperplane's simplex). A vertex *on* the hyperplane (d_i = 0) counts as above it:
//!    the slice is the limit of the slices by n̂·x = offset − ε as ε → 0⁺.
//! 2. A simplex with a vertices above and b below (a + b = N, both > 0) meets the hyperplane in
//!    the product of simplices Δ^{a−1} × Δ^{b−1}, whose vertices are the crossings of the a·b
//!    edges (i above, j below) at `t = d_i / (d_i − d_j)` (eq. 10). A tetrahedron gives a
//!    triangle (a = 1 or b = 1) or a quadrilateral (a = b = 2).
//! 3. That product is cut into (N−2)-simplices by its *staircase triangulation*: the monotone
//!    lattice paths from (0, 0) to (a−1, b−1) through the a × b grid of crossings, C(N−2, a−1)
//!    of them (two triangles for the quadrilateral), with the vertices above and below each
//!    ordered by their index in the mesh. A face shared by two simplices is cut the same way from
//!    both sides (the triangulation restricted to a face is the face's own staircase), so the
//!    output has no cracks: a closed mesh slices into a closed mesh.
//! 4. Crossings are shared across simplices: an edge's crossing is one output vertex, and a
//!    vertex on the hyperplane is one output vertex however many edges reach it. A piece whose
//!    vertices coincide (it collapsed onto the hyperplane) is dropped, each piece is oriented so
//!    that its normal in the slice (eq. 6 in N−1 dimensions) points along the cut simplex's
//!    normal projected into the hyperplane — outward for an outward mesh — and pieces are summed
//!    as a chain: two with the same vertices and opposite orientations cancel (a ridge lying in
//!    the hyperplane, cut from both sides), so no piece is duplicated and none has zero area.
//!
//! Simplices lying in the hyperplane have every vertex above it and give nothing; their
//! neighbours below give the boundary of the flat piece, so the slice of a cube through one of
//! its faces is that face's outline, and a slice that only touches a vertex or an edge from
//! outside is empty.

use crate::error::{NdError, NdResult};
use crate::geometry::simplex_normal;
use crate::linalg::{det, dot, norm, scale, sub, Matrix, Vector};
use crate::mesh::Mesh;
use crate::with_dim;
use rayon::prelude::*;
use std::collections::HashMap;

/// A hyperplane n̂·x = offset with an orthonormal frame of it.
#[derive(Debug, Clone, PartialEq)]
pub struct SlicePlane<const N: usize> {
    /// Unit normal n̂.
    pub normal: Vector<N>,
    /// Signed distance of the hyperplane from the origin along n̂.
    pub offset: f64,
    /// N−1 orthonormal vectors spanning the hyperplane (the rows of the (N−1) × N basis): the
    /// coordinate axes but the one most aligned with n̂, in order, made orthogonal to n̂ and to
    /// each other (for an axis normal, the other axes themselves).
    pub basis: Vec<Vector<N>>,
    /// The hyperplane's point `offset·n̂`, its coordinates' origin: x = origin + Σ y_k·basis_k.
    pub origin: Vector<N>,
}

impl<const N: usize> SlicePlane<N> {
    /// The hyperplane `normal·x = offset·|normal|`, i.e. n̂·x = `offset` with n̂ the unit
    /// `normal` (which need not be unit length). Errors name `normal` (zero, non-finite, wrong
    /// length) or `offset` (non-finite).
    pub fn new(normal: &[f64], offset: f64) -> NdResult<Self> {
        if normal.len() != N {
            return Err(NdError::Shape {
                arg: "normal".into(),
                expected: format!("({N},)"),
                got: format!("({},)", normal.len()),
            });
        }
        let n: Vector<N> = std::array::from_fn(|k| normal[k]);
        let len = norm(&n);
        if !n.iter().all(|x| x.is_finite()) || !(len > 0.0) || !len.is_finite() {
            return Err(NdError::Value {
                arg: "normal".into(),
                message: format!("must be a finite non-zero vector, got {normal:?}"),
            });
        }
        if !offset.is_finite() {
            return Err(NdError::Value {
                arg: "offset".into(),
                message: format!("must be finite, got {offset}"),
            });
        }
        let n = scale(&n, 1.0 / len);
        // Gram–Schmidt of the axes, skipping the one most aligned with n̂.
        let skip = (0..N)
            .max_by(|&a, &b| n[a].abs().total_cmp(&n[b].abs()))
            .unwrap_or(0);
        let mut basis: Vec<Vector<N>> = Vec::with_capacity(N - 1);
        for k in (0..N).filter(|&k| k != skip) {
            let mut e = [0.0; N];
            e[k] = 1.0;
            for _ in 0..2 {
                for b in std::iter::once(&n).chain(basis.iter()) {
                    let c = dot(&e, b);
                    e = std::array::from_fn(|i| e[i] - c * b[i]);
                }
            }
            let l = norm(&e);
            basis.push(scale(&e, 1.0 / l));
        }
        Ok(SlicePlane {
            normal: n,
            offset,
            basis,
            origin: scale(&n, offset),
        })
    }

    /// The coordinates y ∈ R^{N−1} of the point `x` projected into the hyperplane:
    /// `y_k = basis_k·(x − origin)`.
    pub fn coords(&self, x: &Vector<N>) -> Vec<f64> {
        let d = sub(x, &self.origin);
        self.basis.iter().map(|b| dot(b, &d)).collect()
    }

    /// The signed distance n̂·x − offset (eq. 1): > 0 above the hyperplane.
    #[inline]
    pub fn side(&self, x: &Vector<N>) -> f64 {
        dot(&self.normal, x) - self.offset
    }
}

/// Where an output vertex of a slice comes from: the crossing of the edge from vertex `above`
/// to vertex `below` at `x = x_above + t·(x_below − x_above)` (t = 0: the vertex `above` lies on
/// the hyperplane).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Crossing {
    /// The vertex above (or on) the hyperplane.
    pub above: u32,
    /// The vertex below it.
    pub below: u32,
    /// The edge parameter of eq. 10.
    pub t: f64,
}

impl Crossing {
    /// `values` (one per mesh vertex) interpolated at the crossing.
    pub fn interpolate(&self, values: &[f64]) -> f64 {
        let (a, b) = (values[self.above as usize], values[self.below as usize]);
        if self.t == 0.0 {
            a
        } else {
            a + self.t * (b - a)
        }
    }
}

/// The slice of a mesh: its vertices (in R^N, on the hyperplane) with where each comes from,
/// and its (N−2)-simplices, N−1 vertex indices each, with the simplex of the mesh each was cut
/// from.
#[derive(Debug, Clone, PartialEq)]
pub struct Slice<const N: usize> {
    /// The hyperplane and its frame.
    pub plane: SlicePlane<N>,
    /// Output vertices, in R^N.
    pub points: Vec<Vector<N>>,
    /// Per output vertex, the edge crossing it is.
    pub crossings: Vec<Crossing>,
    /// N−1 indices per output simplex, flat.
    pub simplices: Vec<u32>,
    /// Per output simplex, the index of the mesh simplex it was cut from.
    pub parents: Vec<u32>,
}

impl<const N: usize> Slice<N> {
    /// Number of output simplices.
    pub fn len(&self) -> usize {
        self.parents.len()
    }

    /// Whether the slice is empty.
    pub fn is_empty(&self) -> bool {
        self.parents.is_empty()
    }

    /// The output vertices in the hyperplane's coordinates, N−1 per vertex, flat.
    pub fn coords(&self) -> Vec<f64> {
        self.points
            .iter()
            .flat_map(|p| self.plane.coords(p))
            .collect()
    }
}

/// Key of an output vertex: the vertex on the hyperplane, or the edge (above, below).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
enum Key {
    Vertex(u32),
    Edge(u32, u32),
}

/// One cut piece before the vertices are shared: its N−1 keys (oriented) and parent.
struct Piece {
    keys: Vec<Key>,
    parent: u32,
}

/// A path through the grid of crossings: its (i above, j below) points.
type Staircase = Vec<(usize, usize)>;

/// The monotone lattice paths from (0, 0) to (a−1, b−1) (the staircase triangulation of
/// Δ^{a−1} × Δ^{b−1}), each as its a + b − 1 grid points.
fn staircases(a: usize, b: usize) -> Vec<Staircase> {
    let mut out = Vec::new();
    let mut path = vec![(0, 0)];
    fn walk(
        a: usize,
        b: usize,
        path: &mut Vec<(usize, usize)>,
        out: &mut Vec<Vec<(usize, usize)>>,
    ) {
        let (i, j) = *path.last().unwrap();
        if i == a - 1 && j == b - 1 {
            out.push(path.clone());
            return;
        }
        if i + 1 < a {
            path.push((i + 1, j));
            walk(a, b, path, out);
            path.pop();
        }
        if j + 1 < b {
            path.push((i, j + 1));
            walk(a, b, path, out);
            path.pop();
        }
    }
    walk(a, b, &mut path, &mut out);
    out
}

/// The slice of `mesh` by `plane` (steps 1–4 of the module documentation).
pub fn slice<const N: usize>(mesh: &Mesh<N>, plane: &SlicePlane<N>) -> Slice<N> {
    // 1. Sides.
    let d: Vec<f64> = mesh.vertices.par_iter().map(|x| plane.side(x)).collect();
    let above = |i: u32| d[i as usize] >= 0.0;
    // The orientation sign of the frame [basis; n̂] (±1), which turns the sign of an
    // N-determinant into that of the (N−1)-determinant in the hyperplane's coordinates.
    let frame: Matrix<N> = std::array::from_fn(|r| {
        if r + 1 < N {
            plane.basis[r]
        } else {
            plane.normal
        }
    });
    let frame_sign = det(&frame).signum();
    // Per (a, b): the staircases of Δ^{a−1} × Δ^{b−1}.
    let stairs: Vec<Vec<Vec<Staircase>>> = (0..=N)
        .map(|a| {
            (0..=N)
                .map(|b| {
                    if a > 0 && b > 0 {
                        staircases(a, b)
                    } else {
                        vec![]
                    }
                })
                .collect()
        })
        .collect();
    let point = |k: &Key| -> Vector<N> {
        match *k {
            Key::Vertex(i) => mesh.vertices[i as usize],
            Key::Edge(i, j) => {
                let (xi, xj) = (&mesh.vertices[i as usize], &mesh.vertices[j as usize]);
                let t = d[i as usize] / (d[i as usize] - d[j as usize]);
                std::array::from_fn(|c| xi[c] + t * (xj[c] - xi[c]))
            }
        }
    };
    // 2–3. Each simplex's pieces, in simplex order.
    let pieces: Vec<Piece> = mesh
        .simplices
        .par_iter()
        .enumerate()
        .flat_map_iter(|(s, idx)| {
            let mut up: Vec<u32> = idx.iter().copied().filter(|&i| above(i)).collect();
            let mut down: Vec<u32> = idx.iter().copied().filter(|&i| !above(i)).collect();
            let mut out = Vec::new();
            if up.is_empty() || down.is_empty() {
                return out.into_iter();
            }
            up.sort_unstable();
            down.sort_unstable();
            let pts: [Vector<N>; N] = std::array::from_fn(|k| mesh.vertices[idx[k] as usize]);
            let m = simplex_normal(&pts);
            for path in &stairs[up.len()][down.len()] {
                let mut keys: Vec<Key> = path
                    .iter()
                    .map(|&(i, j)| {
                        if d[up[i] as usize] == 0.0 {
                            Key::Vertex(up[i])
                        } else {
                            Key::Edge(up[i], down[j])
                        }
                    })
                    .collect();
                // 4a. Collapsed onto the hyperplane: drop.
                let mut sorted = keys.clone();
                sorted.sort_unstable_by_key(key_order);
                if sorted.windows(2).any(|w| w[0] == w[1]) {
                    continue;
                }
                // 4b. Orientation: sign of det[e_1 … e_{N−2} | m | n̂] times the frame's sign
                // is that of the piece's normal in the slice against m projected into it.
                let p: Vec<Vector<N>> = keys.iter().map(&point).collect();
                let mut cols: Vec<Vector<N>> = p[1..].iter().map(|q| sub(q, &p[0])).collect();
                let scale_of = cols.iter().map(norm).product::<f64>() * norm(&m);
                cols.push(m);
                cols.push(plane.normal);
                let mat: Matrix<N> = std::array::from_fn(|r| std::array::from_fn(|c| cols[c][r]));
                let v = det(&mat) * frame_sign;
                if !(v.abs() > crate::geometry::DEGENERACY_TOLERANCE * scale_of) {
                    continue;
                }
                if v < 0.0 {
                    keys.swap(0, 1);
                }
                out.push(Piece {
                    keys,
                    parent: s as u32,
                });
            }
            out.into_iter()
        })
        .collect();
    // 4c. Shared vertices, and the pieces summed as a chain.
    let mut index: HashMap<Key, u32> = HashMap::new();
    let mut points = Vec::new();
    let mut crossings = Vec::new();
    let mut net: HashMap<Vec<u32>, (i32, usize)> = HashMap::new();
    let mut order: Vec<(Vec<u32>, Vec<u32>, u32)> = Vec::new();
    for piece in &pieces {
        let ids: Vec<u32> = piece
            .keys
            .iter()
            .map(|k| {
                *index.entry(*k).or_insert_with(|| {
                    points.push(point(k));
                    crossings.push(match *k {
                        Key::Vertex(i) => Crossing {
                            above: i,
                            below: i,
                            t: 0.0,
                        },
                        Key::Edge(i, j) => Crossing {
                            above: i,
                            below: j,
                            t: d[i as usize] / (d[i as usize] - d[j as usize]),
                        },
                    });
                    (points.len() - 1) as u32
                })
            })
            .collect();
        let (sorted, parity) = sorted_with_parity(&ids);
        let e = net.entry(sorted.clone()).or_insert((0, order.len()));
        if e.1 == order.len() {
            order.push((sorted, ids, piece.parent));
        }
        e.0 += parity;
    }
    let mut simplices = Vec::new();
    let mut parents = Vec::new();
    for (sorted, ids, parent) in &order {
        let total = net[sorted].0;
        if total == 0 {
            continue;
        }
        let (_, parity) = sorted_with_parity(ids);
        let mut ids = ids.clone();
        if parity != total.signum() {
            ids.swap(0, 1);
        }
        simplices.extend_from_slice(&ids);
        parents.push(*parent);
    }
    // Drop the vertices only cancelled pieces used, renumbering in order of first use.
    let mut renumber = vec![u32::MAX; points.len()];
    let mut kept_points = Vec::new();
    let mut kept_crossings = Vec::new();
    for i in simplices.iter_mut() {
        let r = &mut renumber[*i as usize];
        if *r == u32::MAX {
            *r = kept_points.len() as u32;
            kept_points.push(points[*i as usize]);
            kept_crossings.push(crossings[*i as usize]);
        }
        *i = *r;
    }
    Slice {
        plane: plane.clone(),
        points: kept_points,
        crossings: kept_crossings,
        simplices,
        parents,
    }
}

fn key_order(k: &Key) -> (u32, u32) {
    match *k {
        Key::Vertex(i) => (i, u32::MAX),
        Key::Edge(i, j) => (i, j),
    }
}

/// `ids` sorted, and the sign (±1) of the permutation that sorts them.
fn sorted_with_parity(ids: &[u32]) -> (Vec<u32>, i32) {
    let mut v = ids.to_vec();
    let mut parity = 1;
    // Insertion sort, counting transpositions (N − 1 ≤ 7 entries).
    for i in 1..v.len() {
        let mut j = i;
        while j > 0 && v[j - 1] > v[j] {
            v.swap(j - 1, j);
            parity = -parity;
            j -= 1;
        }
    }
    (v, parity)
}

/// A slice as flat rows with a runtime dimension, for the bindings.
#[derive(Debug, Clone, PartialEq)]
pub struct SliceRows {
    /// Output vertices in the hyperplane's coordinates, (V', N−1) flat.
    pub coords: Vec<f64>,
    /// Output simplices, (S', N−1) flat.
    pub simplices: Vec<u32>,
    /// The basis, (N−1, N) flat.
    pub basis: Vec<f64>,
    /// The origin, N values.
    pub origin: Vec<f64>,
    /// Per output vertex, `values` interpolated (empty without values).
    pub values: Vec<f64>,
    /// Per output simplex, its parent simplex.
    pub parents: Vec<u32>,
}

/// [`slice()`] of the mesh given by flat rows (`vertices` (V, dim), `simplices` (S, dim)),
/// with optional per-vertex `values` interpolated at the crossings. Errors name the argument.
pub fn slice_rows(
    dim: usize,
    vertices: &[f64],
    simplices: &[u32],
    normal: &[f64],
    offset: f64,
    values: Option<&[f64]>,
) -> NdResult<SliceRows> {
    if dim < 3 {
        return Err(NdError::Value {
            arg: "vertices".into(),
            message: format!("slices need N ≥ 3 (a mesh of (N−1)-simplices in R^N), got N = {dim}"),
        });
    }
    with_dim!(dim, N => {
        let mesh = mesh_from_rows::<N>(vertices, simplices)?;
        if let Some(i) = vertices.iter().position(|x| !x.is_finite()) {
            return Err(NdError::Value {
                arg: "vertices".into(),
                message: format!("non-finite value {} at index ({}, {})", vertices[i], i / N, i % N),
            });
        }
        if let Some(v) = values {
            if v.len() != mesh.vertices.len() {
                return Err(NdError::Shape {
                    arg: "values".into(),
                    expected: format!("({},)", mesh.vertices.len()),
                    got: format!("({},)", v.len()),
                });
            }
        }
        let plane = SlicePlane::<N>::new(normal, offset)?;
        let s = slice(&mesh, &plane);
        SliceRows {
            coords: s.coords(),
            basis: s.plane.basis.iter().flatten().copied().collect(),
            origin: s.plane.origin.to_vec(),
            values: values.map_or_else(Vec::new, |v| s.crossings.iter().map(|c| c.interpolate(v)).collect()),
            simplices: s.simplices,
            parents: s.parents,
        }
    })
}

/// The mesh of flat rows, checked: whole rows, indices in range.
fn mesh_from_rows<const N: usize>(vertices: &[f64], simplices: &[u32]) -> NdResult<Mesh<N>> {
    let shape = |arg: &str, len: usize| NdError::Shape {
        arg: arg.into(),
        expected: format!("a multiple of {N} values"),
        got: format!("{len}"),
    };
    if !vertices.len().is_multiple_of(N) {
        return Err(shape("vertices", vertices.len()));
    }
    if !simplices.len().is_multiple_of(N) {
        return Err(shape("simplices", simplices.len()));
    }
    let nv = vertices.len() / N;
    if let Some(i) = simplices.iter().position(|&k| k as usize >= nv) {
        return Err(NdError::Value {
            arg: format!("simplices[{}][{}]", i / N, i % N),
            message: format!(
                "vertex index {} out of range: there are {nv} vertices",
                simplices[i]
            ),
        });
    }
    Ok(Mesh::<N> {
        vertices: vertices
            .chunks_exact(N)
            .map(|v| std::array::from_fn(|k| v[k]))
            .collect(),
        simplices: simplices
            .chunks_exact(N)
            .map(|s| std::array::from_fn(|k| s[k]))
            .collect(),
    })
}

#[cfg(test)]
mod tests;
