//! Generated closed shapes: boundaries of N-dimensional solids tessellated into (N−1)-simplices.
//!
//! The course notes render an N-dimensional object through its (N−1)-dimensional boundary,
//! "tessellated into (N−1)-dimensional simplexes" (section "N-dimensional Imaging"); for 4D
//! shading they suggest tetrahedra with 4D vertices, "or *carefully* subdivide a cubic lattice"
//! (slide "4D Shading"). This module builds both kinds for every N:
//!
//! * [`simplex_boundary`]: the N+1 facets of the regular N-simplex (section "What is a Simplex,
//!   Anyway?", table 1: an N-simplex has N+1 (N−1)-faces).
//! * [`cross_polytope`]: the 2^N facets of the convex hull of ±e_i.
//! * [`hypercube`]: the 2N (N−1)-cube facets of [−1, 1]^N, each cut into (N−1)! simplices by the
//!   Kuhn (Freudenthal) triangulation.
//! * [`sphere`]: the hypercube's facets refined into a cubic lattice, Kuhn-triangulated, and
//!   projected radially onto S^{N−1}.
//!
//! ## Orientation
//! A simplex's normal is the generalized cross product of `x_1 − x_0 … x_{N−1} − x_0` (eq. 6,
//! [`simplex_normal`]). Every generated boundary is closed and consistently oriented with these
//! normals pointing **outward**, so back-face culling and shading (eq. 6 with the view or light
//! vector in the last column) work unchanged. [`orient_outward`] repairs the orientation of any
//! star-shaped mesh, and [`vertex_normals`] gives per-vertex normals for interpolated shading.
//!
//! With outward normals the enclosed volume follows from the divergence theorem as a sum of
//! cones from the origin: `V = Σ_facets N·x_0 / N!`, which in terms of eq. 2–3 volumes is
//! `V = (−1)^(N−1) Σ_facets V_N(0, x_0, …, x_{N−1})`, because
//! `det[x_0 … x_{N−1}] = det[x_0, x_1−x_0, …] = (−1)^(N−1) det[x_1−x_0 … x_{N−1}−x_0 | x_0]`.

use crate::geometry::simplex_normal;
use crate::linalg::{add, dot, norm, scale, sub, Vector};
use crate::mesh::Mesh;
use rayon::prelude::*;

/// Boundary of the regular N-simplex inscribed in the unit sphere, centred at the origin.
///
/// The N+1 vertices satisfy `|v_i| = 1` and `v_i · v_j = −1/N` (i ≠ j). The first N are the rows
/// of the Cholesky factor of their Gram matrix (so vertex i lies in the span of the first i+1 axes);
/// the last is `v_N = −Σ v_i`, which puts the centroid at the origin. Facet i is the (N−1)-simplex
/// opposite vertex i, oriented outward with [`orient_outward`].
pub fn simplex_boundary<const N: usize>() -> Mesh<N> {
    let inv_n = 1.0 / N as f64;
    let mut vertices: Vec<Vector<N>> = Vec::with_capacity(N + 1);
    for i in 0..N {
        // Row i of the lower-triangular L with L·Lᵀ = G, G_ij = 1 (i = j), −1/N (i ≠ j).
        let mut row = [0.0; N];
        for j in 0..i {
            let s: f64 = (0..j).map(|m| row[m] * vertices[j][m]).sum();
            row[j] = (-inv_n - s) / vertices[j][j];
        }
        let s: f64 = (0..i).map(|m| row[m] * row[m]).sum();
        row[i] = (1.0 - s).sqrt();
        vertices.push(row);
    }
    let sum = vertices.iter().fold([0.0; N], |acc, v| add(&acc, v));
    vertices.push(scale(&sum, -1.0));

    let simplices = (0..=N)
        .map(|skip| {
            let mut idx = [0u32; N];
            for (slot, v) in (0..=N).filter(|&v| v != skip).enumerate() {
                idx[slot] = v as u32;
            }
            idx
        })
        .collect();
    let mut mesh = Mesh {
        vertices,
        simplices,
    };
    orient_outward(&mut mesh, [0.0; N]);
    mesh
}

/// Boundary of the hypercube [−1, 1]^N: 2^N vertices (shared) and 2N·(N−1)! simplices.
///
/// Each (N−1)-cube facet `x_a = ±1` is cut by the Kuhn (Freudenthal) triangulation into one
/// simplex per permutation π of its N−1 free axes: starting at the facet's lowest corner, step
/// +2 along axis π(0), then π(1), …, visiting N corners. All facets use the same positive step
/// directions, so neighbouring facets induce the same triangulation on their shared (N−2)-face
/// and the boundary is a closed simplicial manifold. Built as [`sphere`]'s lattice with one
/// cell per facet, without the projection; orientation as described there.
pub fn hypercube<const N: usize>() -> Mesh<N> {
    cube_lattice_surface::<N>(1, false)
}

/// Boundary of the cross-polytope (the N-dimensional octahedron, convex hull of ±e_i):
/// 2N vertices and 2^N facets, one per sign pattern s ∈ {±1}^N, with vertices `s_i·e_i`,
/// oriented outward with [`orient_outward`]. Vertex `2i` is `+e_i`, vertex `2i + 1` is `−e_i`.
pub fn cross_polytope<const N: usize>() -> Mesh<N> {
    let mut vertices = Vec::with_capacity(2 * N);
    for i in 0..N {
        for s in [1.0, -1.0] {
            let mut v = [0.0; N];
            v[i] = s;
            vertices.push(v);
        }
    }
    let simplices = (0..1u32 << N)
        .map(|signs| std::array::from_fn(|i| 2 * i as u32 + ((signs >> i) & 1)))
        .collect();
    let mut mesh = Mesh {
        vertices,
        simplices,
    };
    orient_outward(&mut mesh, [0.0; N]);
    mesh
}

/// The unit sphere S^{N−1} ⊂ R^N, tessellated by "carefully subdividing a cubic lattice" (course
/// notes, "4D Shading") and projecting it radially.
///
/// With `k = 2^subdivisions`, each of the 2N facets of the hypercube [−1, 1]^N is divided into
/// k^(N−1) small (N−1)-cubes, and each small cube into (N−1)! simplices by the Kuhn triangulation
/// (see [`hypercube`]), all with the same positive step directions so that neighbouring simplices
/// share faces exactly, within a facet and across facet boundaries. Lattice points are numbered
/// exactly by their integer coordinates (no floating-point deduplication), then every vertex is
/// projected to the unit sphere.
///
/// Counts: `(k+1)^N − (k−1)^N` vertices and `2N·k^(N−1)·(N−1)!` simplices (3072 for N = 4,
/// `subdivisions = 2`). `subdivisions = 0` is the hypercube scaled by 1/√N.
///
/// Orientation is fixed combinatorially: the Kuhn simplex of permutation π on facet `x_a = ±1`
/// has `N·e_a ∝ sgn(π)·(−1)^(N−1−a)` (eq. 6 with edges reduced to `e_{π(0)}, …, e_{π(N−2)}` by
/// column operations), so its first two vertices are swapped whenever that sign disagrees with
/// the facet's side. Radial projection keeps it: it maps the cube's surface smoothly and
/// orientation-preservingly onto the sphere, and the projected simplices stay non-degenerate.
///
/// # Panics
/// If the vertex count does not fit in `u32` (or the simplex count in `usize`).
pub fn sphere<const N: usize>(subdivisions: u32) -> Mesh<N> {
    assert!(
        subdivisions < 31,
        "sphere: subdivisions = {subdivisions} is far too large"
    );
    cube_lattice_surface::<N>(1 << subdivisions, true)
}

/// The icosphere (N = 3): the icosahedron with every triangle split in four `subdivisions`
/// times, each new vertex the midpoint of an edge pushed onto the unit sphere; 20·4^s triangles,
/// oriented outward. Unlike [`sphere`], whose Kuhn diagonals are reflex on some lattice squares,
/// it is strictly convex at every edge.
pub fn icosphere(subdivisions: u32) -> Mesh<3> {
    let t = (1.0 + 5f64.sqrt()) / 2.0;
    let unit = |p: &Vector<3>| scale(p, 1.0 / norm(p));
    let mut vertices: Vec<Vector<3>> = [
        [-1., t, 0.],
        [1., t, 0.],
        [-1., -t, 0.],
        [1., -t, 0.],
        [0., -1., t],
        [0., 1., t],
        [0., -1., -t],
        [0., 1., -t],
        [t, 0., -1.],
        [t, 0., 1.],
        [-t, 0., -1.],
        [-t, 0., 1.],
    ]
    .iter()
    .map(unit)
    .collect();
    let mut simplices: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..subdivisions {
        let mut mid = std::collections::HashMap::new();
        let mut m = |a: u32, b: u32, v: &mut Vec<Vector<3>>| {
            *mid.entry((a.min(b), a.max(b))).or_insert_with(|| {
                v.push(unit(&scale(&add(&v[a as usize], &v[b as usize]), 0.5)));
                (v.len() - 1) as u32
            })
        };
        simplices = simplices
            .iter()
            .flat_map(|&[a, b, c]| {
                let (ab, bc, ca) = (
                    m(a, b, &mut vertices),
                    m(b, c, &mut vertices),
                    m(c, a, &mut vertices),
                );
                [[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]
            })
            .collect();
    }
    Mesh {
        vertices,
        simplices,
    }
}

/// Per-vertex unit normals for interpolated shading (section "Normals and the Cross-Product",
/// after eq. 6: "compute the normal at each vertex, e.g. by averaging the normals of all
/// neighboring simplexes and normalizing").
///
/// Each vertex gets the normalized sum of the unnormalized generalized cross products (eq. 6) of
/// the simplices around it; since `|N| = (N−1)!·V_{N−1}` (eq. 8), this is the (N−1)-volume
/// weighted average. A vertex whose sum is zero (e.g. one used by no simplex) gets the zero
/// vector.
pub fn vertex_normals<const N: usize>(mesh: &Mesh<N>) -> Vec<Vector<N>> {
    let mut acc = vec![[0.0; N]; mesh.vertices.len()];
    // Normals are computed in parallel chunk by chunk and summed serially in simplex order, so
    // the result does not depend on the number of threads.
    let mut normals = Vec::with_capacity(CHUNK.min(mesh.simplices.len()));
    for (c, chunk) in mesh.simplices.chunks(CHUNK).enumerate() {
        chunk
            .par_iter()
            .enumerate()
            .map(|(i, _)| simplex_normal(&mesh.simplex_points(c * CHUNK + i)))
            .collect_into_vec(&mut normals);
        for (idx, n) in chunk.iter().zip(&normals) {
            for &v in idx {
                acc[v as usize] = add(&acc[v as usize], n);
            }
        }
    }
    acc.par_iter_mut().for_each(|a| {
        let len = norm(a);
        *a = if len > 0.0 {
            scale(a, 1.0 / len)
        } else {
            [0.0; N]
        };
    });
    acc
}

/// Simplices per parallel batch in [`vertex_normals`].
const CHUNK: usize = 1 << 16;

/// Orients every simplex of a star-shaped mesh away from `center`: a simplex whose normal
/// (eq. 6) points toward `center`, i.e. `N · (centroid − center) < 0`, has its first two vertices
/// swapped, which negates its normal. Simplices with `N · (centroid − center) = 0` (degenerate,
/// or whose hyperplane passes through `center`) are left alone.
pub fn orient_outward<const N: usize>(mesh: &mut Mesh<N>, center: Vector<N>) {
    let vertices = &mesh.vertices;
    mesh.simplices.par_iter_mut().for_each(|idx| {
        let p: [Vector<N>; N] = std::array::from_fn(|k| vertices[idx[k] as usize]);
        let n = simplex_normal(&p);
        let centroid = scale(
            &p.iter().fold([0.0; N], |acc, x| add(&acc, x)),
            1.0 / N as f64,
        );
        if dot(&n, &sub(&centroid, &center)) < 0.0 {
            idx.swap(0, 1);
        }
    });
}

/// Exact numbering of the integer points on the boundary of the lattice cube [0, k]^N.
///
/// A boundary point belongs to the facet `(a, side)` of its *smallest* axis `a` with
/// `g_a ∈ {0, k}` (side 0 for 0, side 1 for k). Facet `(a, side)` thus owns the points with
/// `g_b ∈ 1..k` for b < a and `g_b ∈ 0..=k` for b > a, numbered in mixed radix (radix k−1 resp.
/// k+1, the lowest other axis most significant) after `offset[a][side]`.
struct SurfaceLattice<const N: usize> {
    k: u32,
    offset: [[u32; 2]; N],
    len: u32,
}

impl<const N: usize> SurfaceLattice<N> {
    fn new(k: u32) -> Self {
        assert!(k >= 1);
        let mut offset = [[0u32; 2]; N];
        let mut total: u64 = 0;
        for (a, off) in offset.iter_mut().enumerate() {
            let owned = Self::owned_count(k, a).expect("sphere: too many vertices for u32 indices");
            for o in off.iter_mut() {
                *o = u32::try_from(total).expect("sphere: too many vertices for u32 indices");
                total += owned;
            }
        }
        let len = u32::try_from(total).expect("sphere: too many vertices for u32 indices");
        SurfaceLattice { k, offset, len }
    }

    /// Number of points owned by each facet of axis `a`: (k−1)^a · (k+1)^(N−1−a).
    fn owned_count(k: u32, a: usize) -> Option<u64> {
        let lo = u64::from(k - 1).checked_pow(a as u32)?;
        let hi = u64::from(k + 1).checked_pow((N - 1 - a) as u32)?;
        lo.checked_mul(hi)
    }

    /// Index of the boundary lattice point `g`.
    #[inline]
    fn index(&self, g: &[u32; N]) -> u32 {
        let k = self.k;
        let a = (0..N)
            .find(|&b| g[b] == 0 || g[b] == k)
            .expect("point not on the boundary");
        let mut idx = 0u32;
        for b in 0..N {
            if b < a {
                idx = idx * (k - 1) + (g[b] - 1);
            } else if b > a {
                idx = idx * (k + 1) + g[b];
            }
        }
        self.offset[a][(g[a] == k) as usize] + idx
    }

    /// The lattice point with local number `local` among those owned by facet `(a, side)`.
    fn point(&self, a: usize, side: usize, mut local: u32) -> [u32; N] {
        let k = self.k;
        let mut g = [0u32; N];
        g[a] = if side == 1 { k } else { 0 };
        for b in (0..N).rev() {
            if b < a {
                g[b] = local % (k - 1) + 1;
                local /= k - 1;
            } else if b > a {
                g[b] = local % (k + 1);
                local /= k + 1;
            }
        }
        g
    }
}

/// The Kuhn simplices of the unit (N−1)-cube: for each permutation π of the N−1 free axes (in
/// lexicographic order), the chain of corner bitmasks `0, {π0}, {π0, π1}, …` (bit i = free axis
/// i raised) and whether π is odd.
fn kuhn_chains<const N: usize>() -> Vec<([usize; N], bool)> {
    let m = N - 1;
    let mut perm: Vec<usize> = (0..m).collect();
    let mut out = Vec::new();
    loop {
        let mut chain = [0usize; N];
        for i in 0..m {
            chain[i + 1] = chain[i] | (1 << perm[i]);
        }
        let inversions = (0..m).flat_map(|i| (i + 1..m).map(move |j| (i, j)));
        let odd = inversions.filter(|&(i, j)| perm[i] > perm[j]).count() % 2 == 1;
        out.push((chain, odd));
        // Next permutation in lexicographic order.
        let Some(i) = (1..m).rev().find(|&i| perm[i - 1] < perm[i]) else {
            break;
        };
        let j = (i..m).rev().find(|&j| perm[j] > perm[i - 1]).unwrap();
        perm.swap(i - 1, j);
        perm[i..].reverse();
    }
    out
}

/// The Kuhn-triangulated boundary of the lattice cube [0, k]^N mapped to [−1, 1]^N, optionally
/// projected to the unit sphere. See [`sphere`].
fn cube_lattice_surface<const N: usize>(k: u32, project: bool) -> Mesh<N> {
    let lattice = SurfaceLattice::<N>::new(k);

    let step = 2.0 / f64::from(k); // a power of two for the generated k: positions are exact
    let mut vertices = Vec::with_capacity(lattice.len as usize);
    for a in 0..N {
        let owned = SurfaceLattice::<N>::owned_count(k, a).unwrap() as u32;
        for side in 0..2 {
            for local in 0..owned {
                let g = lattice.point(a, side, local);
                debug_assert_eq!(lattice.index(&g) as usize, vertices.len());
                let x: Vector<N> = std::array::from_fn(|b| f64::from(g[b]) * step - 1.0);
                vertices.push(if project {
                    scale(&x, 1.0 / norm(&x))
                } else {
                    x
                });
            }
        }
    }

    let chains = kuhn_chains::<N>();
    let simplex_count = (k as usize)
        .checked_pow((N - 1) as u32)
        .and_then(|c| c.checked_mul(2 * N * chains.len()))
        .expect("sphere: too many simplices");
    let mut simplices: Vec<[u32; N]> = Vec::with_capacity(simplex_count);
    let mut corners = vec![0u32; 1 << (N - 1)];
    for a in 0..N {
        let mut free = [0usize; N];
        for (slot, b) in (0..N).filter(|&b| b != a).enumerate() {
            free[slot] = b;
        }
        let axis_odd = (N - 1 - a) % 2 == 1;
        for side in 0..2 {
            // Swap when sgn(π)·(−1)^(N−1−a) disagrees with the side's sign (see `sphere`).
            let flip_even = axis_odd == (side == 1);
            let mut cell = [0u32; N];
            let mut base = [0u32; N];
            base[a] = if side == 1 { k } else { 0 };
            'cells: loop {
                for i in 0..N - 1 {
                    base[free[i]] = cell[i];
                }
                for (mask, c) in corners.iter_mut().enumerate() {
                    let mut g = base;
                    for i in 0..N - 1 {
                        g[free[i]] += ((mask >> i) & 1) as u32;
                    }
                    *c = lattice.index(&g);
                }
                for (chain, odd) in &chains {
                    let mut s: [u32; N] = std::array::from_fn(|j| corners[chain[j]]);
                    if flip_even != *odd {
                        s.swap(0, 1);
                    }
                    simplices.push(s);
                }
                // Odometer over the k^(N−1) cells of this facet.
                let mut i = 0;
                loop {
                    if i == N - 1 {
                        break 'cells;
                    }
                    cell[i] += 1;
                    if cell[i] < k {
                        break;
                    }
                    cell[i] = 0;
                    i += 1;
                }
            }
        }
    }
    Mesh {
        vertices,
        simplices,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dim::MAX_POINTS;
    use crate::geometry::{hyperplane, signed_volume};
    use crate::linalg::factorial;
    use crate::testutil::{for_each_dim, rng};
    use rand::Rng;

    /// Subdivision levels used per N (indexed by N), chosen to keep the tests fast.
    const COUNT_SUBDIVISIONS: [u32; 9] = [0, 0, 6, 4, 3, 2, 1, 0, 0];
    const CLOSED_SUBDIVISIONS: [u32; 9] = [0, 0, 4, 3, 2, 2, 1, 0, 0];
    const VOLUME_SUBDIVISIONS: [u32; 9] = [0, 0, 6, 4, 3, 3, 1, 1, 0];

    fn all_shapes<const N: usize>(sphere_subdivisions: u32) -> Vec<(String, Mesh<N>)> {
        vec![
            ("simplex".to_string(), simplex_boundary::<N>()),
            ("hypercube".to_string(), hypercube::<N>()),
            ("cross-polytope".to_string(), cross_polytope::<N>()),
            (
                format!("sphere({sphere_subdivisions})"),
                sphere::<N>(sphere_subdivisions),
            ),
        ]
    }

    /// Every (N−2)-face is shared by exactly two simplices that induce opposite orientations.
    ///
    /// The face of `[v_0 … v_{N−1}]` opposite `v_j` carries the boundary orientation
    /// `(−1)^j [v_0 … v̂_j … v_{N−1}]`; relative to the face's sorted vertex list that is the
    /// parity of j plus the inversions of the remaining sequence — equivalently the parity of the
    /// permutation that moves `v_j` to the front and sorts the rest. Two consistently oriented
    /// neighbours must disagree on it.
    fn check_closed_oriented<const N: usize>(mesh: &Mesh<N>) -> Result<(), String> {
        let mut faces: Vec<([u32; N], bool)> = Vec::with_capacity(mesh.simplices.len() * N);
        for (s, idx) in mesh.simplices.iter().enumerate() {
            if idx.iter().any(|&v| v as usize >= mesh.vertices.len()) {
                return Err(format!("simplex {s} {idx:?}: index out of range"));
            }
            for j in 0..N {
                let mut rest = [u32::MAX; N];
                for (slot, m) in (0..N).filter(|&m| m != j).enumerate() {
                    rest[slot] = idx[m];
                }
                let mut inversions = 0;
                for p in 0..N - 1 {
                    for q in p + 1..N - 1 {
                        if rest[p] == rest[q] {
                            return Err(format!("simplex {s} {idx:?}: repeated vertex"));
                        }
                        inversions += (rest[p] > rest[q]) as usize;
                    }
                }
                rest.sort_unstable();
                faces.push((rest, (j + inversions) % 2 == 1));
            }
        }
        faces.sort_unstable();
        let mut i = 0;
        while i < faces.len() {
            let mut j = i;
            while j < faces.len() && faces[j].0 == faces[i].0 {
                j += 1;
            }
            if j - i != 2 {
                return Err(format!(
                    "face {:?} shared by {} simplices",
                    faces[i].0,
                    j - i
                ));
            }
            if faces[i].1 == faces[i + 1].1 {
                return Err(format!(
                    "face {:?}: neighbours induce the same orientation",
                    faces[i].0
                ));
            }
            i = j;
        }
        Ok(())
    }

    /// No degenerate simplex, and every normal points away from the origin. Reports the first
    /// offending simplex (checked in parallel: the N = 8 meshes have 80640 simplices).
    fn check_outward<const N: usize>(mesh: &Mesh<N>) -> Result<(), String> {
        let bad = (0..mesh.simplices.len())
            .into_par_iter()
            .find_map_first(|s| {
                let p = mesh.simplex_points(s);
                let Ok(plane) = hyperplane(&p) else {
                    return Some(format!("simplex {s} is degenerate: {p:?}"));
                };
                let centroid = p.iter().fold([0.0; N], |acc, x| add(&acc, x));
                // `hyperplane`'s unit normal has the direction of `simplex_normal` (eq. 6).
                (!(dot(&plane.normal, &centroid) > 0.0))
                    .then(|| format!("simplex {s} points inward: {p:?}"))
            });
        bad.map_or(Ok(()), Err)
    }

    /// Divergence theorem: V = (−1)^(N−1) Σ V_N(0, x_0, …, x_{N−1}) (see the module docs).
    fn enclosed_volume<const N: usize>(mesh: &Mesh<N>) -> f64 {
        let mut pts = [[0.0; N]; MAX_POINTS];
        let sum: f64 = (0..mesh.simplices.len())
            .map(|s| {
                pts[1..=N].copy_from_slice(&mesh.simplex_points(s));
                signed_volume(&pts[..=N])
            })
            .sum();
        if N % 2 == 1 {
            sum
        } else {
            -sum
        }
    }

    /// Volume of the unit N-ball, π^(N/2)/Γ(N/2 + 1), by V_n = 2π/n · V_(n−2).
    fn unit_ball_volume(n: usize) -> f64 {
        match n {
            0 => 1.0,
            1 => 2.0,
            _ => 2.0 * std::f64::consts::PI / n as f64 * unit_ball_volume(n - 2),
        }
    }

    fn counts<const N: usize>() {
        let fact = factorial(N - 1) as usize;
        let m = simplex_boundary::<N>();
        assert_eq!(
            (m.vertices.len(), m.simplices.len()),
            (N + 1, N + 1),
            "N={N} simplex"
        );
        let m = hypercube::<N>();
        assert_eq!(
            (m.vertices.len(), m.simplices.len()),
            (1 << N, 2 * N * fact),
            "N={N} cube"
        );
        for v in &m.vertices {
            assert!(
                v.iter().all(|&c| c == 1.0 || c == -1.0),
                "N={N}: cube vertex {v:?}"
            );
        }
        let m = cross_polytope::<N>();
        assert_eq!(
            (m.vertices.len(), m.simplices.len()),
            (2 * N, 1 << N),
            "N={N} cross"
        );
        for s in 0..=COUNT_SUBDIVISIONS[N] {
            let k = 1usize << s;
            let m = sphere::<N>(s);
            let verts = (k + 1).pow(N as u32) - (k - 1).pow(N as u32);
            let simps = 2 * N * k.pow(N as u32 - 1) * fact;
            assert_eq!(m.vertices.len(), verts, "N={N} s={s}: sphere vertices");
            assert_eq!(m.simplices.len(), simps, "N={N} s={s}: sphere simplices");
            // Exact deduplication: every vertex is used and no two coincide.
            let mut used = vec![false; m.vertices.len()];
            m.simplices
                .iter()
                .flatten()
                .for_each(|&v| used[v as usize] = true);
            assert!(used.iter().all(|&u| u), "N={N} s={s}: unused vertex");
            let mut bits: Vec<[u64; N]> = m.vertices.iter().map(|v| v.map(f64::to_bits)).collect();
            bits.sort_unstable();
            bits.dedup();
            assert_eq!(bits.len(), verts, "N={N} s={s}: duplicate vertices");
        }
    }

    #[test]
    fn vertex_and_simplex_counts_match_the_formulas() {
        for_each_dim!(counts);
        assert_eq!(hypercube::<4>().simplices.len(), 48);
        assert_eq!(sphere::<4>(2).simplices.len(), 3072);
    }

    fn lattice_numbering<const N: usize>() {
        for k in 1..=3u32 {
            let lattice = SurfaceLattice::<N>::new(k);
            let total = (k as usize + 1).pow(N as u32);
            let mut seen = vec![false; lattice.len as usize];
            for flat in 0..total {
                let mut rem = flat;
                let g: [u32; N] = std::array::from_fn(|_| {
                    let d = rem % (k as usize + 1);
                    rem /= k as usize + 1;
                    d as u32
                });
                if !g.iter().any(|&c| c == 0 || c == k) {
                    continue;
                }
                let i = lattice.index(&g) as usize;
                assert!(i < seen.len() && !seen[i], "N={N} k={k}: {g:?} -> {i}");
                seen[i] = true;
                let a = (0..N).find(|&b| g[b] == 0 || g[b] == k).unwrap();
                let side = (g[a] == k) as usize;
                let local = i as u32 - lattice.offset[a][side];
                assert_eq!(lattice.point(a, side, local), g, "N={N} k={k}: round trip");
            }
            assert!(seen.iter().all(|&s| s), "N={N} k={k}: numbering not onto");
        }
    }

    #[test]
    fn surface_lattice_numbering_is_a_bijection() {
        for_each_dim!(lattice_numbering);
    }

    fn closed_and_oriented<const N: usize>() {
        for (name, mesh) in all_shapes::<N>(CLOSED_SUBDIVISIONS[N]) {
            check_closed_oriented(&mesh).unwrap_or_else(|e| panic!("N={N} {name}: {e}"));
            check_outward(&mesh).unwrap_or_else(|e| panic!("N={N} {name}: {e}"));
        }
    }

    #[test]
    fn shapes_are_closed_consistently_oriented_nondegenerate_and_outward() {
        for_each_dim!(closed_and_oriented);
    }

    fn checkers_reject_broken_meshes<const N: usize>() {
        let mut r = rng(0x5ba9e5 + N as u64);
        // (Meshes over 50000 simplices, the N = 8 hypercube and sphere(0), are skipped for speed.)
        let shapes = all_shapes::<N>(1.min(CLOSED_SUBDIVISIONS[N]));
        for (name, mesh) in shapes
            .into_iter()
            .filter(|(_, m)| m.simplices.len() <= 50_000)
        {
            let s = r.random_range(0..mesh.simplices.len());
            let mut flipped = mesh.clone();
            flipped.simplices[s].swap(0, N - 1);
            assert!(
                check_closed_oriented(&flipped).is_err(),
                "N={N} {name}: flip undetected"
            );
            assert!(
                check_outward(&flipped).is_err(),
                "N={N} {name}: inward undetected"
            );
            let mut holed = mesh.clone();
            holed.simplices.swap_remove(s);
            assert!(
                check_closed_oriented(&holed).is_err(),
                "N={N} {name}: hole undetected"
            );
            let mut flat = mesh.clone();
            let i = flat.simplices[s][0] as usize;
            flat.vertices[i] = flat.vertices[flat.simplices[s][1] as usize];
            assert!(
                check_outward(&flat).is_err(),
                "N={N} {name}: degeneracy undetected"
            );
        }
    }

    #[test]
    fn mesh_checkers_reject_flipped_missing_and_degenerate_simplices() {
        for_each_dim!(checkers_reject_broken_meshes);
    }

    fn volumes<const N: usize>() {
        let n = N as f64;
        let close = |got: f64, want: f64| (got - want).abs() <= 1e-10 * want;
        let cube = enclosed_volume(&hypercube::<N>());
        assert!(
            close(cube, 2f64.powi(N as i32)),
            "N={N}: cube volume {cube}"
        );
        let cross = enclosed_volume(&cross_polytope::<N>());
        assert!(
            close(cross, 2f64.powi(N as i32) / factorial(N)),
            "N={N}: cross {cross}"
        );
        // Regular simplex with circumradius 1: V = (N+1)^((N+1)/2) / (N!·N^(N/2)).
        let simplex = enclosed_volume(&simplex_boundary::<N>());
        let want = (n + 1.0).powf((n + 1.0) / 2.0) / (factorial(N) * n.powf(n / 2.0));
        assert!(close(simplex, want), "N={N}: simplex {simplex} vs {want}");

        // The inscribed sphere tessellations: s = 0 is the hypercube scaled by 1/√N; the volume
        // grows with s towards the ball's, with second-order convergence (error ~ k^(−2)).
        let ball = unit_ball_volume(N);
        let mut errors = vec![];
        for s in 0..=VOLUME_SUBDIVISIONS[N] {
            let v = enclosed_volume(&sphere::<N>(s));
            if s == 0 {
                let want = (2.0 / n.sqrt()).powi(N as i32);
                assert!(close(v, want), "N={N}: sphere(0) {v} vs {want}");
            }
            let err = (ball - v) / ball;
            assert!(
                err > 0.0,
                "N={N} s={s}: inscribed volume {v} exceeds the ball's {ball}"
            );
            if let Some(&prev) = errors.last() {
                assert!(err < prev, "N={N} s={s}: volume {v} did not grow");
                if s >= 3 {
                    assert!(err < 0.35 * prev, "N={N} s={s}: error {err} vs {prev}");
                }
            }
            if s == 3 {
                // Relative error at k = 8 is about 0.7 %, 1.9 %, 3.3 %, 5.0 % for N = 2 … 5.
                let tol = [0.0, 0.0, 0.01, 0.025, 0.04, 0.06][N];
                assert!(
                    err < tol,
                    "N={N}: sphere(3) volume {v} vs ball {ball} ({err})"
                );
            }
            errors.push(err);
        }
    }

    #[test]
    fn enclosed_volumes_by_the_divergence_theorem() {
        assert!((unit_ball_volume(3) - 4.0 / 3.0 * std::f64::consts::PI).abs() < 1e-15);
        assert!((unit_ball_volume(4) - std::f64::consts::PI.powi(2) / 2.0).abs() < 1e-15);
        for_each_dim!(volumes);
    }

    fn regular_simplex<const N: usize>() {
        let m = simplex_boundary::<N>();
        let mut sum = [0.0; N];
        for (i, a) in m.vertices.iter().enumerate() {
            sum = add(&sum, a);
            for (j, b) in m.vertices.iter().enumerate() {
                let want = if i == j { 1.0 } else { -1.0 / N as f64 };
                assert!(
                    (dot(a, b) - want).abs() < 1e-14,
                    "N={N}: v{i}·v{j} = {}",
                    dot(a, b)
                );
            }
        }
        assert!(norm(&sum) < 1e-14, "N={N}: centroid {sum:?}");
    }

    #[test]
    fn simplex_vertices_are_regular_and_on_the_unit_sphere() {
        for_each_dim!(regular_simplex);
    }

    fn normals<const N: usize>() {
        // Sphere: unit vertices, unit vertex normals within O(1/k) of radial (the lattice step
        // subtends about 2/k radians; the Kuhn triangulation is not symmetric, so the
        // area-weighted normal is off by a fraction of that: ~0.5/k at k = 8, ≤ 1/k before).
        for s in 0..=COUNT_SUBDIVISIONS[N] {
            let m = sphere::<N>(s);
            let vn = vertex_normals(&m);
            let mut max_angle: f64 = 0.0;
            for (x, nv) in m.vertices.iter().zip(&vn) {
                assert!(
                    (norm(x) - 1.0).abs() < 1e-14,
                    "N={N} s={s}: |x| = {}",
                    norm(x)
                );
                assert!(
                    (norm(nv) - 1.0).abs() < 1e-12,
                    "N={N} s={s}: |n| = {}",
                    norm(nv)
                );
                max_angle = max_angle.max(dot(x, nv).clamp(-1.0, 1.0).acos());
            }
            let k = f64::from(1u32 << s);
            let bound = if s >= 3 { 0.6 / k } else { 1.2 / k };
            assert!(
                max_angle < bound,
                "N={N} s={s}: vertex normal {max_angle} rad off radial"
            );
        }
        // The polytopes: unit vertex normals pointing away from the origin.
        for (name, m) in all_shapes::<N>(0)
            .into_iter()
            .filter(|(name, _)| name != "sphere(0)")
        {
            for (x, nv) in m.vertices.iter().zip(vertex_normals(&m)) {
                assert!(
                    (norm(&nv) - 1.0).abs() < 1e-12,
                    "N={N} {name}: |n| = {}",
                    norm(&nv)
                );
                assert!(
                    dot(x, &nv) > 0.0,
                    "N={N} {name}: vertex normal points inward"
                );
            }
        }
        // By symmetry the simplex's and cross-polytope's vertex normals are radial.
        for m in [simplex_boundary::<N>(), cross_polytope::<N>()] {
            for (x, nv) in m.vertices.iter().zip(vertex_normals(&m)) {
                assert!((dot(x, &nv) - 1.0).abs() < 1e-12, "N={N}: not radial");
            }
        }
    }

    #[test]
    fn vertex_normals_are_unit_and_radial_on_the_sphere() {
        for_each_dim!(normals);
    }

    fn zero_normal_sums<const N: usize>() {
        // The simplex (0, e_1, …, e_{N−1}) twice with opposite orientations, plus an unused
        // vertex: integer coordinates make the cancellation exact.
        let mut vertices = vec![[0.0; N]];
        for i in 0..N - 1 {
            let mut e = [0.0; N];
            e[i] = 1.0;
            vertices.push(e);
        }
        vertices.push([1.0; N]);
        let s: [u32; N] = std::array::from_fn(|i| i as u32);
        let mut t = s;
        t.swap(0, 1);
        let pair = Mesh {
            vertices: vertices.clone(),
            simplices: vec![s, t],
        };
        assert!(
            vertex_normals(&pair).iter().all(|n| *n == [0.0; N]),
            "N={N}: nonzero"
        );
        // A single simplex: its vertices get its unit normal +e_N·(sign), the unused one zero.
        let single = Mesh {
            vertices,
            simplices: vec![s],
        };
        let vn = vertex_normals(&single);
        let mut want = [0.0; N];
        want[N - 1] = 1.0;
        for v in 0..N {
            assert!(norm(&sub(&vn[v], &want)) < 1e-15, "N={N}: {:?}", vn[v]);
        }
        assert_eq!(vn[N], [0.0; N], "N={N}: unused vertex");
    }

    #[test]
    fn vertex_normals_of_cancelling_or_unused_vertices_are_zero() {
        for_each_dim!(zero_normal_sums);
    }

    fn orientation_repair<const N: usize>() {
        let mut r = rng(0x0e1e7 + N as u64);
        // (The 80640-simplex N = 8 hypercube and sphere(0) are skipped for speed; their
        // orientation is checked by `shapes_are_closed_…`.)
        let shapes = all_shapes::<N>(1.min(CLOSED_SUBDIVISIONS[N]));
        for (name, mesh) in shapes
            .into_iter()
            .filter(|(_, m)| m.simplices.len() <= 50_000)
        {
            // Already outward: unchanged.
            let mut same = mesh.clone();
            orient_outward(&mut same, [0.0; N]);
            assert_eq!(
                same, mesh,
                "N={N} {name}: orient_outward changed an outward mesh"
            );
            // Random flips are undone exactly (swapping 0 and 1 twice is the identity).
            let mut flipped = mesh.clone();
            let mut count = 0;
            for s in &mut flipped.simplices {
                if r.random_bool(0.5) {
                    s.swap(0, 1);
                    count += 1;
                }
            }
            assert!(count > 0 || mesh.simplices.len() < 8);
            orient_outward(&mut flipped, [0.0; N]);
            assert_eq!(flipped, mesh, "N={N} {name}: flips not repaired");
            // A far-away center flips the facets facing it.
            let mut far = mesh.clone();
            let mut center = [0.0; N];
            center[0] = 100.0;
            orient_outward(&mut far, center);
            assert_ne!(far, mesh, "N={N} {name}: far center changed nothing");
        }
    }

    #[test]
    fn orient_outward_repairs_random_flips() {
        for_each_dim!(orientation_repair);
    }
}
