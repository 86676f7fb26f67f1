//! Whole-tracer speed (camera rays, BVH, shading, shadow rays, retina writes) on one scene file,
//! and how much of the closest-hit cost is memory rather than arithmetic.
//!
//! `cargo run --release -p ndtrace --example trace_speed -- SCENE.toml [REPEATS] [THREADS]`
//!
//! Traces the scene `REPEATS` times (default 5) on a pool of `THREADS` rayon workers (default
//! one) and prints the best wall-clock and, with one thread, the best thread-CPU rate in rays
//! (retina cells) per second: CPU time is what other processes competing for the cores do not
//! distort. Also prints a hash of the retina, so that a change can be checked to leave every
//! bit of the output unchanged. `perf record` on this binary shows where the time goes.
//!
//! With `--features traversal-stats` it also prints, per cell (primary and shadow rays
//! together), the node visits (one per packet), the per-ray node box tests and the per-ray leaf
//! tests; the tree's size and depth are always printed.
//!
//! `… --example trace_speed -- SCENE.toml orders` instead times closest-hit queries alone
//! (one thread, no shading or shadow rays) for the rays through the cell centres taken in
//! image order, all equal to one ray (everything cached: the arithmetic and latency floor),
//! in random order (cache-hostile), and for a ray that misses the root box (the fixed cost of
//! a query), one ray per call; then the image-order rays as packets of 8 (as the tracer sends
//! them), one packet over and over, and the shadow rays from their hits toward the first light
//! one by one and as packets.

mod common;

use common::thread_seconds;
use ndtrace::ray::Ray;
use ndtrace::render::{trace, Progress, Retina};
use ndtrace::scene::{load_file, Scene};
use ndtrace::with_scene;
use std::hash::{Hash, Hasher};
use std::path::Path;
use std::time::Instant;

/// A hash of every output array of the retina, bit for bit.
fn retina_hash(r: &Retina) -> u64 {
    let mut h = std::collections::hash_map::DefaultHasher::new();
    r.rgba.iter().for_each(|v| v.to_bits().hash(&mut h));
    r.depth.iter().for_each(|v| v.to_bits().hash(&mut h));
    r.normal.iter().for_each(|v| v.to_bits().hash(&mut h));
    r.object_id.hash(&mut h);
    r.primitive_id.hash(&mut h);
    h.finish()
}

/// The least thread-CPU time of three runs of `f`.
fn best_cpu_seconds(mut f: impl FnMut()) -> f64 {
    (0..3)
        .map(|_| {
            let c0 = thread_seconds().unwrap_or(f64::NAN);
            f();
            thread_seconds().unwrap_or(f64::NAN) - c0
        })
        .fold(f64::INFINITY, f64::min)
}

/// Closest-hit rates for the same rays in different orders (see the module docs).
fn orders<const N: usize>(scene: &Scene<N>) {
    let cam = &scene.camera;
    let n = cam.cell_count();
    let centre = vec![0.5; N - 1];
    let mut rays: Vec<Ray<N>> = (0..n)
        .map(|c| {
            let mut u = [0.0; N];
            cam.retina_point(c, &centre, &mut u);
            cam.ray(&u[..N - 1])
        })
        .collect();
    let mut away = rays[0];
    away.dir = away.dir.map(|x| -x);
    rays.push(away);
    // A fixed-seed Fisher–Yates shuffle (an LCG), so that runs are comparable.
    let mut random: Vec<usize> = (0..n).collect();
    let mut state = 12345u64;
    for i in (1..n).rev() {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        random.swap(i, (state >> 33) as usize % (i + 1));
    }
    // The cell at the middle of every retina axis.
    let (mut middle, mut stride) = (0, 1);
    for &r in &cam.resolution {
        middle += r / 2 * stride;
        stride *= r;
    }
    let runs = [
        ("image order", (0..n).collect::<Vec<_>>()),
        ("one ray", vec![middle; n]),
        ("random order", random),
        ("miss", vec![n; n]),
    ];
    for (name, order) in runs {
        let mut hits = 0;
        let best = best_cpu_seconds(|| {
            hits = order
                .iter()
                .filter(|&&i| {
                    let hit = scene
                        .bvh
                        .closest_hit(&rays[i], 0.0, f64::INFINITY, |_| true);
                    hit.is_some()
                })
                .count();
        });
        println!(
            "{name:>12}: {hits} hits of {n}, {:.2} M closest-hit queries/s CPU",
            n as f64 / best / 1e6
        );
    }
    // The same rays in image order as packets, then shadow rays from their hits toward the
    // first light (a point light's position, or far along a directional light's direction).
    rays.truncate(n);
    let mut out = vec![None; n];
    // One packet (the 8 cells from the middle along u_1), over and over: everything cached.
    let same: Vec<Ray<N>> = (0..n).map(|i| rays[middle + i % 8]).collect();
    for (name, rays) in [("packets", &rays), ("one packet", &same)] {
        let best = best_cpu_seconds(|| {
            scene
                .bvh
                .closest_hits(rays, 0.0, f64::INFINITY, |_| true, &mut out)
        });
        let hits = out.iter().filter(|h| h.is_some()).count();
        println!(
            "{name:>12}: {hits} hits of {n}, {:.2} M closest-hit queries/s CPU",
            n as f64 / best / 1e6
        );
    }
    let Some(light) = scene.lights.first() else {
        return;
    };
    scene
        .bvh
        .closest_hits(&rays, 0.0, f64::INFINITY, |_| true, &mut out);
    let (mut shadow, mut tmax) = (vec![], vec![]);
    for (ray, hit) in rays.iter().zip(&out) {
        let Some(hit) = hit else { continue };
        let x = ray.at(hit.t);
        let to = match light {
            ndtrace::scene::Light::Point { position, .. } => *position,
            ndtrace::scene::Light::Directional { direction, .. } => {
                std::array::from_fn(|i| x[i] + 1e3 * direction[i])
            }
        };
        let d: [f64; N] = std::array::from_fn(|i| to[i] - x[i]);
        let len = d.iter().map(|v| v * v).sum::<f64>().sqrt();
        let n = hit.normal;
        let side = if (0..N).map(|i| n[i] * d[i]).sum::<f64>() >= 0.0 {
            1e-7
        } else {
            -1e-7
        };
        shadow.push(Ray {
            origin: std::array::from_fn(|i| x[i] + side * n[i]),
            dir: d.map(|v| v / len),
        });
        tmax.push(len - 1e-7);
    }
    let mut blocked = vec![false; shadow.len()];
    for (name, packets) in [("shadow rays", false), ("shadow packets", true)] {
        let best = best_cpu_seconds(|| {
            if packets {
                scene
                    .bvh
                    .any_hits(&shadow, 0.0, &tmax, |_| true, 0..0, &mut blocked);
            } else {
                for (i, r) in shadow.iter().enumerate() {
                    blocked[i] = scene.bvh.any_hit(r, 0.0, tmax[i], |_| true, 0..0);
                }
            }
        });
        let count = blocked.iter().filter(|&&b| b).count();
        println!(
            "{name:>12}: {count} blocked of {}, {:.2} M any-hit queries/s CPU",
            shadow.len(),
            shadow.len() as f64 / best / 1e6
        );
    }
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let path = args
        .get(1)
        .expect("usage: trace_speed SCENE.toml [REPEATS [THREADS] | orders]");
    let t0 = Instant::now();
    let (_, scene) = load_file(Path::new(path)).expect("scene");
    let build = t0.elapsed().as_secs_f64();
    with_scene!(&scene, s, _N => println!(
        "tree: {} simplices, {} nodes, {} leaves, depth {}",
        s.bvh.len(),
        s.bvh.node_count(),
        s.bvh.leaf_count(),
        s.bvh.depth()
    ));
    if args.get(2).map(String::as_str) == Some("orders") {
        with_scene!(&scene, s, N => orders::<N>(s));
        return;
    }
    let repeats: usize = args.get(2).map_or(5, |s| s.parse().expect("REPEATS"));
    let threads: usize = args.get(3).map_or(1, |s| s.parse().expect("THREADS"));
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("pool");
    let (mut wall, mut cpu, mut hash, mut cells) = (f64::INFINITY, f64::INFINITY, 0, 0);
    for _ in 0..repeats {
        let (w, c, r) = pool.install(|| {
            let c0 = thread_seconds();
            let t = Instant::now();
            let r =
                with_scene!(&scene, s, N => trace::<N>(s, &Progress::default())).expect("trace");
            let w = t.elapsed().as_secs_f64();
            let c = match (c0, thread_seconds()) {
                (Some(a), Some(b)) if threads == 1 => b - a,
                _ => f64::NAN,
            };
            (w, c, r)
        });
        wall = wall.min(w);
        cpu = cpu.min(c);
        hash = retina_hash(&r);
        cells = r.depth.len();
    }
    #[cfg(feature = "traversal-stats")]
    {
        let [nodes, leaves, slabs] = ndtrace::accel::traversal_stats();
        let rays = (repeats * cells) as f64;
        println!(
            "per retina cell: {:.2} node visits (per packet), {:.2} node slab tests and {:.2} \
             leaf tests (per ray)",
            nodes as f64 / rays,
            slabs as f64 / rays,
            leaves as f64 / rays
        );
    }
    println!(
        "{path}: build {build:.3} s, {cells} cells, {threads} thread(s): {:.2} Mrays/s wall, \
         {:.2} Mrays/s CPU, retina hash {hash:016x}",
        cells as f64 / wall / 1e6,
        cells as f64 / cpu / 1e6
    );
}
