//! BVH build and single-thread traversal speed.
//!
//! `cargo run --release -p ndtrace --example bvh_speed`
//!
//! * 4D: a cubed 3-sphere (the tesseract's boundary, each cubic facet cut into k³ cubes of 6
//!   Kuhn tetrahedra, projected onto the unit 3-sphere): k = 4 gives 3,072 tetrahedra. A pinhole
//!   at distance 3 casts 128³ = 2,097,152 rays through a cubic 3D retina; about half miss.
//! * 3D: an icosphere subdivided 8 times (1,310,720 triangles), 1448² ≈ 2.1M rays, half missing.
//! * 4D: a soup of 3,072 random small tetrahedra in [−1, 1]⁴, same camera.
//! * 4D build stress: the cubed 3-sphere with k = 32 (1,572,864 tetrahedra), built with all
//!   threads and with one (the trees must be identical), then traced.
//!
//! Ray rates are per thread-CPU-second (Linux), so that other processes competing for the cores
//! do not distort them; wall-clock rates are printed alongside.

mod common;

use common::thread_seconds;
use ndtrace::accel::{simplex_bounds, Bounds, Bvh, PreparedSimplex};
use ndtrace::ray::Ray;
use rayon::prelude::*;
use std::time::Instant;

/// `count` random tetrahedra of size ~`size` in [−1, 1]⁴ (a fixed LCG, so runs are comparable).
fn soup4(count: usize, size: f64) -> Vec<[[f64; 4]; 4]> {
    let mut state = 0x2545_f491_4f6c_dd1du64;
    let mut next = move || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (state >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    };
    (0..count)
        .map(|_| {
            let c: [f64; 4] = std::array::from_fn(|_| next() * (1.0 - size));
            std::array::from_fn(|_| std::array::from_fn(|i| c[i] + size * next()))
        })
        .collect()
}

/// All permutations of 0..m.
fn permutations(m: usize) -> Vec<Vec<usize>> {
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

/// The boundary of [−1, 1]^N, each facet cut into k^(N−1) cubes of (N−1)! Kuhn simplices,
/// projected onto the unit sphere.
fn cubed_sphere<const N: usize>(k: usize) -> Vec<[[f64; N]; N]> {
    let perms = permutations(N - 1);
    let mut out = vec![];
    for axis in 0..N {
        for side in [0usize, k] {
            let free: Vec<usize> = (0..N).filter(|&a| a != axis).collect();
            let cells = k.pow(N as u32 - 1);
            for cell in 0..cells {
                let mut base = [0usize; N];
                base[axis] = side;
                let mut c = cell;
                for &a in &free {
                    base[a] = c % k;
                    c /= k;
                }
                for p in &perms {
                    let mut g = base;
                    let mut simplex = [[0.0; N]; N];
                    for j in 0..N {
                        if j > 0 {
                            g[free[p[j - 1]]] += 1;
                        }
                        let x: [f64; N] =
                            std::array::from_fn(|i| 2.0 * g[i] as f64 / k as f64 - 1.0);
                        let l = x.iter().map(|v| v * v).sum::<f64>().sqrt();
                        simplex[j] = std::array::from_fn(|i| x[i] / l);
                    }
                    out.push(simplex);
                }
            }
        }
    }
    out
}

/// An icosahedron subdivided `levels` times, on the unit sphere.
fn icosphere(levels: u32) -> Vec<[[f64; 3]; 3]> {
    let m = ndtrace::shapes::icosphere(levels);
    (0..m.simplices.len())
        .map(|i| m.simplex_points(i))
        .collect()
}

/// Runs `f` and returns (wall seconds, thread CPU seconds or wall seconds).
fn timed(mut f: impl FnMut()) -> (f64, f64) {
    let c0 = thread_seconds();
    let t0 = Instant::now();
    f();
    let wall = t0.elapsed().as_secs_f64();
    let cpu = match (c0, thread_seconds()) {
        (Some(a), Some(b)) => b - a,
        _ => wall,
    };
    (wall, cpu)
}

fn build<const N: usize>(name: &str, simplices: &[[[f64; N]; N]]) -> Bvh<N> {
    let t0 = Instant::now();
    let prepared: Vec<(PreparedSimplex<N>, u32, Bounds<N>)> = simplices
        .par_iter()
        .enumerate()
        .filter_map(|(i, p)| Some((PreparedSimplex::new(p)?, i as u32, simplex_bounds(p))))
        .collect();
    let prep = t0.elapsed().as_secs_f64();
    let (mut prims, mut ids, mut bounds) = (vec![], vec![], vec![]);
    for (p, id, b) in prepared {
        prims.push(p);
        ids.push(id);
        bounds.push(b);
    }
    let t1 = Instant::now();
    let bvh = Bvh::build(prims, ids, bounds);
    let dt = t1.elapsed().as_secs_f64();
    println!(
        "{name}: {} simplices; prepared in {prep:.3} s, BVH built in {dt:.3} s ({} threads); \
         {} nodes, {} leaves, depth {}, {:.1} MB = {:.1} bytes/simplex",
        bvh.len(),
        rayon::current_num_threads(),
        bvh.node_count(),
        bvh.leaf_count(),
        bvh.depth(),
        bvh.memory_bytes() as f64 / 1e6,
        bvh.memory_bytes() as f64 / bvh.len() as f64
    );
    bvh
}

/// Calls `visit` with the `count` rays from `origin` through the pixel centres of the cubic
/// retina with per-axis coordinates `coord` (an odometer over the pixels, no divisions).
#[inline(always)]
fn pixels<const N: usize>(
    origin: [f64; N],
    coord: &[f64],
    count: usize,
    visit: &mut dyn FnMut(&Ray<N>),
) {
    let mut idx = [0usize; N];
    let mut ray = Ray {
        origin,
        dir: [1.0; N],
    };
    for d in ray.dir.iter_mut().take(N - 1) {
        *d = coord[0];
    }
    for _ in 0..count {
        visit(&ray);
        for i in 0..N - 1 {
            idx[i] += 1;
            if idx[i] < coord.len() {
                ray.dir[i] = coord[idx[i]];
                break;
            }
            idx[i] = 0;
            ray.dir[i] = coord[0];
        }
    }
}

/// Times closest_hit and any_hit over the rays of a pinhole at distance 3 on the last axis,
/// through a cubic retina of `res^(N−1)` pixels spanning [−f, f] per axis.
fn trace<const N: usize>(bvh: &Bvh<N>, res: usize, f: f64) {
    let count = res.pow(N as u32 - 1);
    let mut origin = [0.0; N];
    origin[N - 1] = -3.0;
    // Pixel-centre coordinates along one retina axis, and an odometer over the pixels (the
    // ray generation should cost next to nothing next to the traversal).
    let coord: Vec<f64> = (0..res)
        .map(|j| f * (2.0 * (j as f64 + 0.5) / res as f64 - 1.0))
        .collect();
    let for_each_ray = |visit: &mut dyn FnMut(&Ray<N>)| pixels(origin, &coord, count, visit);
    let (mut wall, mut cpu) = (f64::INFINITY, f64::INFINITY);
    let mut hits = 0usize;
    let mut tsum = 0.0;
    for _ in 0..3 {
        let (w, c) = timed(|| {
            hits = 0;
            tsum = 0.0;
            for_each_ray(&mut |ray| {
                if let Some(h) = bvh.closest_hit(ray, 0.0, f64::INFINITY, |_| true) {
                    hits += 1;
                    tsum += h.t + h.bary[0];
                }
            });
        });
        wall = wall.min(w);
        cpu = cpu.min(c);
    }
    println!(
        "  closest_hit: {count} rays, {:.1}% hit, {:.2} M rays/s ({:.2} M rays/s wall; checksum {tsum:.6})",
        100.0 * hits as f64 / count as f64,
        count as f64 / cpu / 1e6,
        count as f64 / wall / 1e6
    );
    let (mut wall, mut cpu) = (f64::INFINITY, f64::INFINITY);
    let mut any = 0usize;
    for _ in 0..3 {
        let (w, c) = timed(|| {
            any = 0;
            for_each_ray(&mut |ray| {
                any += bvh.any_hit(ray, 0.0, f64::INFINITY, |_| true, 0..0) as usize;
            });
        });
        wall = wall.min(w);
        cpu = cpu.min(c);
    }
    assert_eq!(any, hits);
    println!(
        "  any_hit:     {count} rays, {:.2} M rays/s ({:.2} M rays/s wall)",
        count as f64 / cpu / 1e6,
        count as f64 / wall / 1e6
    );
}

fn main() {
    let s4 = cubed_sphere::<4>(4);
    let bvh4 = build("4D cubed 3-sphere k=4", &s4);
    trace(&bvh4, 128, 0.36);

    let soup = soup4(3072, 0.15);
    let bvh_soup = build("4D soup of random tetrahedra", &soup);
    trace(&bvh_soup, 128, 0.36);

    let s3 = icosphere(8);
    let bvh3 = build("3D icosphere level 8", &s3);
    trace(&bvh3, 1448, 0.443);

    let big = cubed_sphere::<4>(32);
    let bvh_big = build("4D cubed 3-sphere k=32", &big);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let again = pool.install(|| build("4D cubed 3-sphere k=32, one thread", &big));
    assert!(again == bvh_big, "the tree depends on the thread count");
    trace(&bvh_big, 128, 0.36);
}
