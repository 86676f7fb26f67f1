//! What the tests of the accelerator's parts share (each part's tests are beside it, in
//! `<part>/tests.rs`): random simplices and rays, brute force, soups of simplices, and the
//! imports they all use.

pub(super) use super::build::{binary_tree, refs_of, PAR_MIN};
pub(super) use super::packet::PACKET;
pub(super) use super::simplex::{simplex_bounds, Bounds, PreparedSimplex};
pub(super) use super::tree::{Bvh, BLOCK_WIDTH, EMPTY_SLOT, LEAF_TAG};
pub(super) use crate::geometry::{barycentric, ray_hyperplane};
pub(super) use crate::linalg::{add, add_scaled, mat_vec, norm, scale, Matrix, Vector};
pub(super) use crate::ray::{Hit, Ray};
pub(super) use crate::testutil::{for_each_dim, random_rotation, random_vector, rng, TestRng};
pub(super) use rand::Rng;
pub(super) use std::collections::HashSet;

/// Random simplex with vertices `center + random_vector(size)`.
pub(super) fn random_simplex<const N: usize>(
    r: &mut TestRng,
    center: &Vector<N>,
    size: f64,
) -> [[f64; N]; N] {
    std::array::from_fn(|_| add(center, &random_vector::<N>(r, size)))
}

/// A point of the simplex's hyperplane with random barycentric weights in [lo, hi] (then
/// normalized to sum 1).
pub(super) fn plane_point<const N: usize>(
    r: &mut TestRng,
    pts: &[[f64; N]; N],
    lo: f64,
    hi: f64,
) -> Vector<N> {
    let mut w: Vec<f64> = (0..N).map(|_| r.random_range(lo..hi)).collect();
    let s: f64 = w.iter().sum();
    w.iter_mut().for_each(|x| *x /= s);
    let mut x = [0.0; N];
    for (p, wi) in pts.iter().zip(&w) {
        x = add_scaled(&x, *wi, p);
    }
    x
}

/// An affine map of the cube tests: the identity for `shape` 0, else a random rotation with
/// random stretches in [0.5, 2) and a random shift.
pub(super) fn random_affine<const N: usize>(
    r: &mut TestRng,
    shape: usize,
) -> (Matrix<N>, Vector<N>) {
    if shape == 0 {
        return (crate::linalg::identity(), [0.0; N]);
    }
    let q = random_rotation::<N>(r);
    let d: Vector<N> = std::array::from_fn(|_| r.random_range(0.5..2.0));
    (
        std::array::from_fn(|i| std::array::from_fn(|j| q[i][j] * d[j])),
        random_vector(r, 3.0),
    )
}

/// A random unit vector (uniform direction).
pub(super) fn random_unit<const N: usize>(r: &mut TestRng) -> Vector<N> {
    loop {
        let v = random_vector::<N>(r, 1.0);
        let l = norm(&v);
        if l > 0.1 && l <= 1.0 {
            return scale(&v, 1.0 / l);
        }
    }
}

/// Brute force over all simplices: the minimum of (t, id) over accepted hits.
pub(super) fn brute<const N: usize>(
    prims: &[(PreparedSimplex<N>, u32)],
    ray: &Ray<N>,
    tmin: f64,
    tmax: f64,
    accept: impl Fn(u32) -> bool,
) -> Option<Hit<N>> {
    brute_with(
        prims,
        ray,
        (tmin, tmax),
        accept,
        PreparedSimplex::intersect_stored,
    )
}

/// [`brute`] with the exact test of every simplex: what a tree that keeps exact rows
/// ([`Bvh::keep_exact_rows`]) finds.
pub(super) fn brute_exact<const N: usize>(
    prims: &[(PreparedSimplex<N>, u32)],
    ray: &Ray<N>,
    tmin: f64,
    tmax: f64,
    accept: impl Fn(u32) -> bool,
) -> Option<Hit<N>> {
    brute_with(prims, ray, (tmin, tmax), accept, PreparedSimplex::intersect)
}

type RayTest<const N: usize> =
    fn(&PreparedSimplex<N>, &Ray<N>, f64, f64) -> Option<(f64, [f64; N])>;

fn brute_with<const N: usize>(
    prims: &[(PreparedSimplex<N>, u32)],
    ray: &Ray<N>,
    (tmin, tmax): (f64, f64),
    accept: impl Fn(u32) -> bool,
    test: RayTest<N>,
) -> Option<Hit<N>> {
    let mut best: Option<Hit<N>> = None;
    for (p, id) in prims {
        if !accept(*id) {
            continue;
        }
        if let Some((t, bary)) = test(p, ray, tmin, tmax) {
            if best.is_none_or(|b| t < b.t || (t == b.t && *id < b.prim)) {
                best = Some(Hit {
                    t,
                    prim: *id,
                    bary,
                    normal: p.rounded_rows()[0],
                });
            }
        }
    }
    best
}

/// A soup of `count` small random simplices (plus a few large ones and exact duplicates with
/// other ids, which tie exactly), with scattered ids.
pub(super) fn soup<const N: usize>(r: &mut TestRng, count: usize) -> Vec<([[f64; N]; N], u32)> {
    let mut out = vec![];
    for i in 0..count {
        let size = if i % 50 == 0 { 1.5 } else { 0.35 };
        let c = random_vector::<N>(r, 2.0);
        out.push((random_simplex(r, &c, size), (7 * i as u32 + 3) ^ 0x55));
    }
    for j in 0..count / 20 {
        let (pts, id) = out[j * 7 % count];
        out.push((pts, id ^ 0x1000));
    }
    out
}

pub(super) fn prepare<const N: usize>(
    soup: &[([[f64; N]; N], u32)],
) -> Vec<(PreparedSimplex<N>, u32)> {
    soup.iter()
        .filter_map(|(p, id)| Some((PreparedSimplex::new(p)?, *id)))
        .collect()
}

pub(super) fn build_soup<const N: usize>(soup: &[([[f64; N]; N], u32)], par_min: usize) -> Bvh<N> {
    let mut prims = vec![];
    let mut ids = vec![];
    let mut bounds = vec![];
    for (p, id) in soup {
        if let Some(ps) = PreparedSimplex::new(p) {
            prims.push(ps);
            ids.push(*id);
            bounds.push(simplex_bounds(p));
        }
    }
    Bvh::build_with(prims, ids, bounds, par_min)
}

/// Rays for packet tests, of kind `kind`: 0 a pinhole (one origin, directions fanned
/// around an aim at a simplex), 1 shadow-like (spread origins aimed near one point), 2
/// random, 3 like 0 with one direction component exactly zero in every ray.
pub(super) fn packet_rays<const N: usize>(
    r: &mut TestRng,
    s: &[([[f64; N]; N], u32)],
    kind: usize,
    count: usize,
) -> Vec<Ray<N>> {
    let origin = random_vector::<N>(r, 3.5);
    let (pts, _) = &s[r.random_range(0..s.len())];
    let aim = plane_point(r, pts, 0.0, 1.0);
    let spread = [0.01, 0.1][r.random_range(0..2)];
    (0..count)
        .map(|_| match kind {
            0 | 3 => {
                let to = add(&aim, &random_vector::<N>(r, spread));
                let mut dir = crate::linalg::sub(&to, &origin);
                if kind == 3 {
                    dir[0] = 0.0;
                }
                Ray { origin, dir }
            }
            1 => {
                let o = add(&aim, &random_vector::<N>(r, spread));
                let light = add(&origin, &random_vector::<N>(r, spread));
                Ray {
                    origin: o,
                    dir: crate::linalg::sub(&light, &o),
                }
            }
            _ => Ray {
                origin: random_vector::<N>(r, 3.5),
                dir: random_vector::<N>(r, 1.0),
            },
        })
        .collect()
}

/// All permutations of 0..m.
pub(super) fn permutations(m: usize) -> Vec<Vec<usize>> {
    if m == 0 {
        return vec![vec![]];
    }
    let mut out = vec![];
    for p in permutations(m - 1) {
        for pos in 0..=p.len() {
            let mut q = p.clone();
            q.insert(pos, m - 1);
            out.push(q);
        }
    }
    out
}

/// The boundary of the cube [0, k]^N on the integer grid: each facet cut into k^(N−1) unit
/// cubes of (N−1)! Kuhn simplices. Kuhn triangulations of neighbouring cubes and facets
/// agree on shared faces, so the mesh is closed and conforming.
pub(super) fn cube_boundary<const N: usize>(k: i64) -> Vec<[[i64; N]; N]> {
    let perms = permutations(N - 1);
    let mut out = vec![];
    for axis in 0..N {
        for side in [0, k] {
            let free: Vec<usize> = (0..N).filter(|&a| a != axis).collect();
            for cell in 0..k.pow(N as u32 - 1) {
                let mut base = [0i64; N];
                base[axis] = side;
                let mut c = cell;
                for &a in &free {
                    base[a] = c % k;
                    c /= k;
                }
                for p in &perms {
                    let mut g = base;
                    out.push(std::array::from_fn(|j| {
                        if j > 0 {
                            g[free[p[j - 1]]] += 1;
                        }
                        g
                    }));
                }
            }
        }
    }
    out
}
