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
mod tests;
