//! The tracer: rays from the N-D camera through every cell of the (N−1)-D retina, nearest hits
//! from the BVH, N-D Lambert + Blinn–Phong shading with hard shadows (course notes, "Ray
//! Tracing" and Part II(B) "4D Shading"), written into a [`Retina`].
//!
//! Work is split into fixed chunks of cells traced in parallel with rayon. Within a chunk, the
//! camera rays of neighbouring cells go to the BVH as packets ([`crate::accel::PACKET`] rays),
//! and the shadow rays of their hits as packets toward each light; a ray's hit does not depend
//! on the rays it travels with. Every cell's result depends only on the scene, the seed and the
//! cell index, so the retina is bit-identical whatever the number of threads.

use crate::accel::{BOX_PAD, PACKET};
use crate::camera::CentreRays;
use crate::linalg::{add_scaled, dot, norm, scale, sub, Vector};
use crate::pool;
use crate::ray::{Hit, Ray};
use crate::scene::desc::RenderMode;
use crate::scene::{Light, Scene};
use crate::{NdError, NdResult};
use rayon::prelude::*;
use std::ops::Range;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

/// Cells per unit of parallel work (and of progress reporting and cancellation checks) of a
/// retina whose chunks are not whole strips of rows (see [`chunking`]).
pub const CHUNK: usize = 4096;
/// Rows of a strip and columns of a tile of the tracing order (see [`tile_order`]).
const TILE: usize = 8;

/// A traced (N−1)-D retina. Arrays are C-ordered in numpy order `[i_{N−1}, …, i_1]`.
#[derive(Debug, Clone, PartialEq)]
pub struct Retina {
    /// Dimension N of the scene.
    pub dim: usize,
    /// Retina shape in numpy order `[R_{N−1}, …, R_1]`.
    pub shape: Vec<usize>,
    /// Linear RGBA, premultiplied by alpha (the covered fraction of the cell).
    pub rgba: Vec<f32>,
    /// Distance to the nearest hit (see [`crate::camera::Camera::depth`]); inf on a miss.
    pub depth: Vec<f32>,
    /// Unit shading normal of the nearest hit (N per cell); zero on a miss.
    pub normal: Vec<f32>,
    /// Object index of the nearest hit; −1 on a miss.
    pub object_id: Vec<i32>,
    /// Index into that object's simplices; −1 on a miss.
    pub primitive_id: Vec<i64>,
}

/// Shared progress of a trace: cells done, and a flag that cancels it.
#[derive(Debug, Default)]
pub struct Progress {
    /// Cells finished so far.
    pub done: AtomicUsize,
    /// Set to stop the trace early (it then returns [`NdError::Cancelled`]).
    pub cancel: AtomicBool,
}

/// SplitMix64: a small, fast, seedable generator for the sample jitter.
#[derive(Clone)]
struct SplitMix(u64);

impl SplitMix {
    fn new(seed: u64, cell: u64) -> Self {
        let mut s = SplitMix(seed ^ 0x9e37_79b9_7f4a_7c15u64.wrapping_mul(cell.wrapping_add(1)));
        s.next();
        s
    }
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }
    /// Uniform in [0, 1).
    fn unit(&mut self) -> f64 {
        (self.next() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }
    fn below(&mut self, n: usize) -> usize {
        (((self.next() >> 32) * n as u64) >> 32) as usize
    }
}

/// Fractional sample positions inside a cell: the centre for one sample; otherwise stratified
/// jitter (a Latin hypercube: along every retina axis each of the S strata holds one sample).
fn sample_offsets(samples: usize, axes: usize, rng: &mut SplitMix, out: &mut Vec<f64>) {
    out.clear();
    out.resize(samples * axes, 0.5);
    if samples == 1 {
        return;
    }
    let mut perm: Vec<usize> = (0..samples).collect();
    for k in 0..axes {
        for i in (1..samples).rev() {
            perm.swap(i, rng.below(i + 1));
        }
        for (j, &p) in perm.iter().enumerate() {
            out[j * axes + k] = (p as f64 + rng.unit()) / samples as f64;
        }
    }
}

/// What a cell records of its nearest hit.
#[derive(Clone, Copy)]
struct NearestHit<const N: usize> {
    depth: f64,
    normal: Vector<N>,
    object: i32,
    primitive: i64,
}

impl<const N: usize> NearestHit<N> {
    /// The record of a miss, as the retina holds it.
    const MISS: Self = NearestHit {
        depth: f64::INFINITY,
        normal: [0.0; N],
        object: -1,
        primitive: -1,
    };
}

/// Traces every retina cell of `scene` (on the current rayon pool).
pub fn trace<const N: usize>(scene: &Scene<N>, progress: &Progress) -> NdResult<Retina> {
    // Back-face culling (course notes): discard a simplex when det[x_1−x_0 … | C − x_0] < 0,
    // i.e. when its normal points away from the eye. The eye is fixed per trace.
    if scene.render.cull_backfaces {
        let culled: Vec<bool> = (0..scene.flat_normals.len())
            .into_par_iter()
            .map(|g| {
                let (o, s) = scene.locate(g as u32);
                let obj = &scene.objects[o];
                let x0 = obj.mesh.vertices[obj.mesh.simplices[s][0] as usize];
                dot(&scene.flat_normals[g], &scene.camera.toward_eye(&x0)) < 0.0
            })
            .collect();
        trace_with(scene, progress, |id| !culled[id as usize])
    } else {
        trace_with(scene, progress, |_| true)
    }
}

fn trace_with<const N: usize, F>(
    scene: &Scene<N>,
    progress: &Progress,
    accept: F,
) -> NdResult<Retina>
where
    F: Fn(u32) -> bool + Sync,
{
    let cam = &scene.camera;
    let cells = cam.cell_count();
    // Kept buffers when the last retina's were handed back ([`crate::pool`]), not cleared: the
    // loop writes every element of every cell, misses included.
    let mut rgba = pool::take::<f32>(cells * 4);
    let mut depth = pool::take::<f32>(cells);
    let mut normal = pool::take::<f32>(cells * N);
    let mut object_id = pool::take::<i32>(cells);
    let mut primitive_id = pool::take::<i64>(cells);
    let samples = scene.render.samples as usize;
    // Only the depth mode uses it (it reads every vertex).
    let depth_range = match scene.render.mode {
        RenderMode::Depth => depth_range(scene),
        _ => (0.0, 1.0),
    };

    // Cells are traced in groups whose rays fill four packets (all samples of a cell go
    // together), so that the fewer shadow rays of a group still fill their packets.
    let group = (4 * PACKET / samples).max(1);
    let row = cam.resolution[0];
    let (chunk_cells, tiled) = chunking(row, N - 1);
    // The order of a whole chunk, when there is one (the last chunk may be shorter).
    let tiles = (tiled && chunk_cells <= cells).then(|| tile_order(row, chunk_cells / row));
    // One sample per cell: its centre.
    let centre = CentreRays::new(cam);
    let shading = ObjectShading::all(scene);
    rgba.par_chunks_mut(chunk_cells * 4)
        .zip(depth.par_chunks_mut(chunk_cells))
        .zip(normal.par_chunks_mut(chunk_cells * N))
        .zip(object_id.par_chunks_mut(chunk_cells))
        .zip(primitive_id.par_chunks_mut(chunk_cells))
        .enumerate()
        .for_each(
            |(chunk, ((((rgba, depth), normal), object_id), primitive_id))| {
                if progress.cancel.load(Ordering::Relaxed) {
                    return;
                }
                let mut work = Work::default();
                let mut offsets = Vec::with_capacity(samples * (N - 1));
                let mut u = [0.0; N];
                let mut idx = [0; N];
                cam.cell_index(chunk * chunk_cells, &mut idx);
                // Tiled order when the chunks are whole rows: the multi-index of the first cell
                // of each row of the chunk.
                let len = depth.len();
                let short;
                let tiled = match &tiles {
                    Some(t) if t.len() == len => Some(t.as_slice()),
                    _ if tiled => {
                        short = tile_order(row, len / row);
                        Some(short.as_slice())
                    }
                    _ => None,
                };
                let mut rows = Vec::new();
                if tiled.is_some() {
                    for _ in 0..len / row {
                        rows.push(idx);
                        idx[0] = row - 1;
                        cam.next_cell(&mut idx);
                    }
                }
                for first in (0..len).step_by(group) {
                    // Slots of the processing order, and the chunk's cell in each.
                    let slots = first..(first + group).min(len);
                    let cell_of = |s: usize| tiled.map_or(s, |t| t[s].0 as usize);
                    work.rays.clear();
                    for s in slots.clone() {
                        let c = cell_of(s);
                        if let Some(t) = tiled {
                            let (_, r, col) = t[s];
                            idx = rows[r as usize];
                            idx[0] = col as usize;
                        }
                        if samples == 1 {
                            work.rays.push(centre.ray(&idx));
                        } else {
                            let cell = chunk * chunk_cells + c;
                            let mut rng = SplitMix::new(scene.render.seed, cell as u64);
                            sample_offsets(samples, N - 1, &mut rng, &mut offsets);
                            for f in offsets.chunks(N - 1) {
                                cam.cell_point(&idx, f, &mut u);
                                work.rays.push(cam.ray(&u[..N - 1]));
                            }
                        }
                        if tiled.is_none() {
                            cam.next_cell(&mut idx);
                        }
                    }
                    work.trace(scene, &accept, &shading, depth_range);
                    for (j, s) in slots.enumerate() {
                        let c = cell_of(s);
                        let (px, nearest) = cell_sum(&work.color, &work.nearest, j, samples);
                        rgba[c * 4..c * 4 + 4].copy_from_slice(&px);
                        let nc: &mut [f32; N] =
                            (&mut normal[c * N..(c + 1) * N]).try_into().unwrap();
                        depth[c] = nearest.depth as f32;
                        for k in 0..N {
                            nc[k] = nearest.normal[k] as f32;
                        }
                        object_id[c] = nearest.object;
                        primitive_id[c] = nearest.primitive;
                    }
                }
                progress.done.fetch_add(depth.len(), Ordering::Relaxed);
            },
        );
    if progress.cancel.load(Ordering::Relaxed) {
        return Err(NdError::Cancelled);
    }
    Ok(Retina {
        dim: N,
        shape: cam.numpy_shape(),
        rgba,
        depth,
        normal,
        object_id,
        primitive_id,
    })
}

/// The value of the `j`-th cell of a group from its `samples` rays (rays `j·samples …` of
/// `colors` and `hits`): premultiplied RGBA, the mean of their colours (misses' are 0) and the
/// fraction that hit, and the nearest hit ([`NearestHit::MISS`] if none).
#[inline(always)]
fn cell_sum<'a, const N: usize>(
    colors: &[[f64; 3]],
    hits: &'a [NearestHit<N>],
    j: usize,
    samples: usize,
) -> ([f32; 4], &'a NearestHit<N>) {
    if samples == 1 {
        // The loop below for one ray (the same bits: x·1 = x), without its overhead.
        let (col, h) = (&colors[j], &hits[j]);
        let a = if h.object >= 0 { 1.0 } else { 0.0 };
        return (
            [0.0 + col[0], 0.0 + col[1], 0.0 + col[2], a].map(|x| x as f32),
            h,
        );
    }
    let rays = j * samples..(j + 1) * samples;
    let inv = 1.0 / samples as f64;
    let mut color = [0.0f64; 3];
    let mut covered = 0usize;
    let mut nearest = &NearestHit::MISS;
    for (col, h) in colors[rays.clone()].iter().zip(&hits[rays]) {
        if h.object < 0 {
            continue;
        }
        covered += 1;
        for k in 0..3 {
            color[k] += col[k];
        }
        if nearest.object < 0 || h.depth < nearest.depth {
            nearest = h;
        }
    }
    let px = [color[0], color[1], color[2], covered as f64].map(|x| (x * inv) as f32);
    (px, nearest)
}

/// Cells per chunk for rows of `row` cells on a retina of `axes` axes, and whether chunks are
/// whole rows traced in [`tile_order`]: with two axes or more, whole strips of [`TILE`] rows, as
/// many as make at least `CHUNK` cells, unless one strip would exceed `4·CHUNK` cells; else
/// (one axis, or very long rows) `CHUNK` cells in memory order.
fn chunking(row: usize, axes: usize) -> (usize, bool) {
    let strip = TILE * row;
    if axes >= 2 && strip <= 4 * CHUNK {
        (strip * CHUNK.div_ceil(strip), true)
    } else {
        (CHUNK, false)
    }
}

/// The order in which the cells of a chunk of `rows` whole rows of `row` cells are traced
/// (retinas of at least two axes): by strips of [`TILE`] rows (the last may have fewer), each
/// strip by tiles of `TILE` columns (the last may have fewer), each tile by pairs of rows, each
/// pair by packets of `PACKET/2` columns × 2 rows. A packet's rays are then closer together
/// than along one row (fewer node visits per packet), and consecutive packets meet mostly the
/// same leaves, still in cache: on a 1.3 M-triangle icosphere at 512², 8×8 tiles trace about 3%
/// faster than strips of two rows. Slot s of the order holds `(cell, row, column)`,
/// chunk-relative.
fn tile_order(row: usize, rows: usize) -> Vec<(u32, u32, u32)> {
    let w = PACKET / 2;
    let mut order = Vec::with_capacity(row * rows);
    for r0 in (0..rows).step_by(TILE) {
        let r_end = (r0 + TILE).min(rows);
        for c0 in (0..row).step_by(TILE) {
            let c_end = (c0 + TILE).min(row);
            for pair in (r0..r_end).step_by(2) {
                for col0 in (c0..c_end).step_by(w) {
                    for r in pair..(pair + 2).min(r_end) {
                        for col in col0..(col0 + w).min(c_end) {
                            order.push(((r * row + col) as u32, r as u32, col as u32));
                        }
                    }
                }
            }
        }
    }
    order
}

/// Near and far depth of the scene's bounding sphere, for the `depth` debug mode.
fn depth_range<const N: usize>(scene: &Scene<N>) -> (f64, f64) {
    let mut lo = [f64::INFINITY; N];
    let mut hi = [f64::NEG_INFINITY; N];
    for o in &scene.objects {
        for v in &o.mesh.vertices {
            for k in 0..N {
                lo[k] = lo[k].min(v[k]);
                hi[k] = hi[k].max(v[k]);
            }
        }
    }
    if !lo[0].is_finite() {
        return (0.0, 1.0);
    }
    let centre: Vector<N> = std::array::from_fn(|k| 0.5 * (lo[k] + hi[k]));
    let radius = 0.5 * norm(&sub(&hi, &lo));
    let view = scene.camera.axis(N - 1);
    let d = dot(&sub(&centre, &scene.camera.position), &view);
    let (near, far) = ((d - radius).max(0.0), d + radius);
    if far > near {
        (near, far)
    } else {
        (near, near + 1.0)
    }
}

/// A distinct, stable colour per global primitive id.
fn id_color(id: u32) -> [f64; 3] {
    let mut h = SplitMix(id as u64);
    let v = h.next();
    std::array::from_fn(|k| 0.25 + 0.75 * (((v >> (k * 16)) & 0xffff) as f64 / 65535.0))
}

/// The unit shading normal: flat (eq. 6) or interpolated from vertex normals with the hit's
/// barycentric coordinates; turned toward the viewer for two-sided lighting.
#[inline(always)]
fn shading_normal<const N: usize>(
    scene: &Scene<N>,
    hit: &Hit<N>,
    obj: usize,
    local: usize,
    ray: &Ray<N>,
) -> Vector<N> {
    let flat = hit.normal;
    let mut n = flat;
    let o = &scene.objects[obj];
    if let Some(vn) = &o.vertex_normals {
        let idx = &o.mesh.simplices[local];
        let mut s = [0.0; N];
        for k in 0..N {
            s = add_scaled(&s, hit.bary[k], &vn[idx[k] as usize]);
        }
        let l = norm(&s);
        if l > 0.0 {
            n = scale(&s, 1.0 / l);
        }
    }
    if scene.render.two_sided && dot(&flat, &ray.dir) > 0.0 {
        n = scale(&n, -1.0);
    }
    n
}

/// The per-group buffers of a trace: the camera rays of a group of cells, their hits, and the
/// shadow rays their shading asks for, each traced as packets.
#[derive(Default)]
struct Work<const N: usize> {
    rays: Vec<Ray<N>>,
    hits: Vec<Option<Hit<N>>>,
    /// Per camera ray: its colour (ambient and the light terms added at once, then those
    /// added after the shadow pass; 0 on a miss) and its nearest-hit record
    /// ([`NearestHit::MISS`] on a miss).
    color: Vec<[f64; 3]>,
    nearest: Vec<NearestHit<N>>,
    /// Light contributions (camera ray, colour) added after the shadow pass (a ray's terms from
    /// its first that waits for a shadow ray on), in ray order then light order; `shadow[i]` is
    /// the index of the term's shadow ray, if it has one.
    terms: Vec<(usize, [f64; 3])>,
    shadow: Vec<Option<usize>>,
    /// Shadow rays in light order (coherent packets), their tmax and their results.
    shadow_rays: Vec<Ray<N>>,
    shadow_tmax: Vec<f64>,
    blocked: Vec<bool>,
    /// (light, term, shadow ray) as shading asks for them.
    requests: Vec<(usize, usize, Shadow<N>)>,
}

/// What shading needs of an object and its material, computed once per trace.
struct ObjectShading {
    /// The ambient term: material ambient × scene ambient × material colour, per channel.
    ambient: [f64; 3],
    /// The diffuse coefficient: material diffuse × material colour, per channel.
    diffuse: [f64; 3],
    /// Whether the material has a specular term.
    specular: bool,
    /// The object's global simplex ids.
    ids: Range<u32>,
    /// Whether they are all the scene's.
    whole_scene: bool,
}

impl ObjectShading {
    /// The constants of every object of `scene`, in object order.
    fn all<const N: usize>(scene: &Scene<N>) -> Vec<Self> {
        let all = 0..scene.flat_normals.len() as u32;
        (0..scene.objects.len())
            .map(|obj| {
                let m = &scene.objects[obj].material;
                let ids = scene.ids(obj);
                ObjectShading {
                    ambient: std::array::from_fn(|k| m.ambient[k] * scene.ambient[k] * m.color[k]),
                    diffuse: std::array::from_fn(|k| m.diffuse[k] * m.color[k]),
                    specular: m.specular.iter().any(|&s| s > 0.0),
                    whole_scene: ids == all,
                    ids,
                }
            })
            .collect()
    }
}

/// A shadow ray: the light counts unless a simplex whose id lies outside `skip` is hit with t in
/// (0, tmax). `skip` holds the ids of the object hit when that object is convex and the ray
/// leaves it on the outer side ([`crate::convex`]), else it is empty.
#[derive(Clone, Debug)]
struct Shadow<const N: usize> {
    ray: Ray<N>,
    tmax: f64,
    skip: Range<u32>,
}

impl<const N: usize> Work<N> {
    /// Traces `self.rays` and shades their hits into `self.color` and `self.nearest`.
    fn trace(
        &mut self,
        scene: &Scene<N>,
        accept: &(impl Fn(u32) -> bool + Sync),
        shading: &[ObjectShading],
        depth_range: (f64, f64),
    ) {
        let cam = &scene.camera;
        // Sized to the rays (no clearing: `closest_hits` writes every element).
        self.hits.resize(self.rays.len(), None);
        scene
            .bvh
            .closest_hits(&self.rays, 0.0, f64::INFINITY, accept, &mut self.hits);
        self.color.clear();
        self.nearest.clear();
        self.terms.clear();
        self.shadow.clear();
        let requests = &mut self.requests;
        requests.clear();
        for (r, (ray, hit)) in self.rays.iter().zip(&self.hits).enumerate() {
            let Some(hit) = hit else {
                self.color.push([0.0; 3]);
                self.nearest.push(NearestHit::MISS);
                continue;
            };
            let (obj, local) = scene.locate(hit.prim);
            let n = shading_normal(scene, hit, obj, local, ray);
            let dir_len = norm(&ray.dir);
            let depth = cam.depth(hit.t, dir_len);
            let c = match scene.render.mode {
                RenderMode::Shaded => {
                    let sh = &shading[obj];
                    let mut c = sh.ambient;
                    // Terms are summed in light order: directly until one waits for its shadow
                    // ray, then after the shadow pass.
                    let mut waiting = false;
                    light_terms(scene, ray, dir_len, hit, obj, sh, &n, |l, color, shadow| {
                        if shadow.is_none() && !waiting {
                            for k in 0..3 {
                                c[k] += color[k];
                            }
                            return;
                        }
                        waiting = true;
                        if let Some(shadow) = shadow {
                            requests.push((l, self.terms.len(), shadow));
                        }
                        // Set to the shadow ray's index once the rays are in light order.
                        self.shadow.push(None);
                        self.terms.push((r, color));
                    });
                    c
                }
                RenderMode::Depth => {
                    let g = 1.0
                        - 0.8
                            * ((depth - depth_range.0) / (depth_range.1 - depth_range.0))
                                .clamp(0.0, 1.0);
                    [g; 3]
                }
                RenderMode::Normal => {
                    std::array::from_fn(|k| if k < N { 0.5 + 0.5 * n[k] } else { 0.5 })
                }
                RenderMode::PrimitiveId => id_color(hit.prim),
                RenderMode::Barycentric => {
                    std::array::from_fn(|k| if k < N { hit.bary[k] } else { 0.0 })
                }
            };
            let nearest = NearestHit {
                depth,
                normal: n,
                object: obj as i32,
                primitive: local as i64,
            };
            self.color.push(c);
            self.nearest.push(nearest);
        }
        if !requests.is_empty() {
            // Light order, so that each packet holds rays toward one light, then by the ids
            // skipped, which a packet shares.
            if scene.lights.len() > 1 || scene.objects.len() > 1 {
                requests.sort_by_key(|q| (q.0, q.2.skip.start, q.2.skip.end));
            }
            self.shadow_rays.clear();
            self.shadow_tmax.clear();
            for (i, (_, term, shadow)) in requests.iter().enumerate() {
                self.shadow[*term] = Some(i);
                self.shadow_rays.push(shadow.ray);
                self.shadow_tmax.push(shadow.tmax);
            }
            self.blocked.clear();
            self.blocked.resize(requests.len(), false);
            let mut first = 0;
            for run in requests.chunk_by(|a, b| a.2.skip == b.2.skip) {
                let all = first..first + run.len();
                scene.bvh.any_hits(
                    &self.shadow_rays[all.clone()],
                    0.0,
                    &self.shadow_tmax[all.clone()],
                    |_| true,
                    run[0].2.skip.clone(),
                    &mut self.blocked[all],
                );
                first += run.len();
            }
        }
        // Contributions in light order per ray (the order of the sum, as for one ray alone).
        for (i, &(r, color)) in self.terms.iter().enumerate() {
            if self.shadow[i].is_some_and(|s| self.blocked[s]) {
                continue;
            }
            let c = &mut self.color[r];
            for k in 0..3 {
                c[k] += color[k];
            }
        }
    }
}

/// Shadow rays start this fraction of the scene's diagonal off the surface, toward the light.
/// The inside test widens every simplex, within its hyperplane, by its `BARY_SLACK` band: at
/// most [`BOX_PAD`] of the simplex's extent, so of the scene's, beyond its boundary. A hit in
/// that band just past a convex ridge, moved off by ten times the band or more (checked at
/// compile time), lies on the outer side of the neighbouring simplex too, for folds up to
/// atan(10) ≈ 84° between the two hyperplanes; so the shadow ray does not start behind it.
const SHADOW_OFFSET: f64 = 1e-7;
const _: () = assert!(SHADOW_OFFSET >= 10.0 * BOX_PAD);

/// N-D Lambert + Blinn–Phong (course notes Part II(B)): calls `emit` per light that faces the
/// surface, in light order, with its index, its colour contribution and the shadow ray that
/// decides whether it counts (none when nothing could block it). The intensity of a light is
/// the dot product of the unit normal with the unit vector toward it, clamped at 0 (lights
/// behind the surface contribute nothing and need no shadow ray). `dir_len` is |ray.dir|.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn light_terms<const N: usize>(
    scene: &Scene<N>,
    ray: &Ray<N>,
    dir_len: f64,
    hit: &Hit<N>,
    obj: usize,
    sh: &ObjectShading,
    n: &Vector<N>,
    mut emit: impl FnMut(usize, [f64; 3], Option<Shadow<N>>),
) {
    let o = &scene.objects[obj];
    let m = &o.material;
    let x = add_scaled(&ray.origin, hit.t, &ray.dir);
    // The unit vector toward the viewer, for the specular term only.
    let v = sh.specular.then(|| scale(&ray.dir, -1.0 / dir_len));
    let flat = hit.normal;
    let eps = SHADOW_OFFSET * scene.extent;
    for (index, light) in scene.lights.iter().enumerate() {
        let (l, dist, color, atten) = match light {
            Light::Directional { direction, color } => (*direction, f64::INFINITY, color, 1.0),
            Light::Point {
                position,
                color,
                falloff,
            } => {
                let d = sub(position, &x);
                let dist = norm(&d);
                if !(dist > 0.0) {
                    continue;
                }
                let atten = if *falloff == 0.0 {
                    1.0
                } else {
                    dist.powf(-falloff)
                };
                (scale(&d, 1.0 / dist), dist, color, atten)
            }
        };
        let ndl = dot(n, &l);
        if ndl <= 0.0 {
            continue;
        }
        let shadow = if scene.render.shadows {
            // Leave the surface on the light's side of the simplex's hyperplane.
            let along = dot(&flat, &l) >= 0.0;
            // A convex object lies on one side of the hyperplane: a ray leaving on the other
            // side never meets it again (nor anything, when the object is all the scene).
            let skips = o.convex == Some(along);
            (!(skips && sh.whole_scene)).then(|| Shadow {
                ray: Ray {
                    origin: add_scaled(&x, if along { eps } else { -eps }, &flat),
                    dir: l,
                },
                tmax: dist - eps,
                skip: if skips { sh.ids.clone() } else { 0..0 },
            })
        } else {
            None
        };
        let spec = if let Some(v) = &v {
            // Blinn–Phong: the half vector of the light and viewer directions.
            let s = add_scaled(&l, 1.0, v);
            let len = norm(&s);
            let h = if len > 0.0 { scale(&s, 1.0 / len) } else { l };
            dot(n, &h).max(0.0).powf(m.shininess)
        } else {
            0.0
        };
        let c = std::array::from_fn(|k| {
            atten * color[k] * (sh.diffuse[k] * ndl + m.specular[k] * spec)
        });
        emit(index, c, shadow);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::linalg::det;
    use crate::scene::load_toml_str;

    /// One cell, one ray at a time, with the single-ray queries: the colour sum and nearest hit
    /// (the first sample of least depth) the packet path must reproduce bit for bit, the
    /// samples that hit, and the shadow rays blocked. Camera rays see the simplices `accept`s.
    fn one_ray_at_a_time<const N: usize>(
        scene: &Scene<N>,
        cell: usize,
        accept: &dyn Fn(u32) -> bool,
    ) -> ([f64; 3], NearestHit<N>, usize, usize) {
        let samples = scene.render.samples as usize;
        let mut rng = SplitMix::new(scene.render.seed, cell as u64);
        let mut offsets = vec![];
        sample_offsets(samples, N - 1, &mut rng, &mut offsets);
        let (mut color, mut covered, mut blocked) = ([0.0; 3], 0, 0);
        let mut nearest = NearestHit::MISS;
        let mut u = [0.0; N];
        for j in 0..samples {
            scene
                .camera
                .retina_point(cell, &offsets[j * (N - 1)..(j + 1) * (N - 1)], &mut u);
            let ray = scene.camera.ray(&u[..N - 1]);
            let Some(hit) = scene.bvh.closest_hit(&ray, 0.0, f64::INFINITY, accept) else {
                continue;
            };
            covered += 1;
            let (obj, local) = scene.locate(hit.prim);
            let n = shading_normal(scene, &hit, obj, local, &ray);
            let m = &scene.objects[obj].material;
            let mut c: [f64; 3] =
                std::array::from_fn(|k| m.ambient[k] * scene.ambient[k] * m.color[k]);
            let dir_len = norm(&ray.dir);
            let depth = scene.camera.depth(hit.t, dir_len);
            if covered == 1 || depth < nearest.depth {
                nearest = NearestHit {
                    depth,
                    normal: n,
                    object: obj as i32,
                    primitive: local as i64,
                };
            }
            let sh = &ObjectShading::all(scene)[obj];
            // The per-object constants both sides use, checked against the material (the
            // ambient term above is computed from it directly).
            let diffuse: [f64; 3] = std::array::from_fn(|k| m.diffuse[k] * m.color[k]);
            assert_eq!(sh.diffuse.map(f64::to_bits), diffuse.map(f64::to_bits));
            assert_eq!(sh.specular, m.specular != [0.0; 3]);
            assert_eq!(sh.ids, scene.ids(obj));
            assert_eq!(
                sh.whole_scene,
                sh.ids.start == 0 && sh.ids.end == scene.flat_normals.len() as u32
            );
            light_terms(
                scene,
                &ray,
                dir_len,
                &hit,
                obj,
                sh,
                &n,
                |_, term, shadow| {
                    if shadow
                        .is_some_and(|s| scene.bvh.any_hit(&s.ray, 0.0, s.tmax, |_| true, s.skip))
                    {
                        blocked += 1;
                        return;
                    }
                    for k in 0..3 {
                        c[k] += term[k];
                    }
                },
            );
            for k in 0..3 {
                color[k] += c[k];
            }
        }
        (color, nearest, covered, blocked)
    }

    /// Every cell's RGBA has the bits of [`one_ray_at_a_time`]; returns the cells hit and the
    /// cells with a blocked shadow ray.
    fn shade_as_one_ray_at_a_time<const N: usize>(scene: &Scene<N>) -> (usize, usize) {
        // Back-face culling (course notes): a simplex is culled when
        // det[x_1 − x_0 … x_{N−1} − x_0 | C − x_0] < 0, here the determinant itself (the
        // tracer takes the dot product of the flat normal with C − x_0).
        let culled: Vec<bool> = (0..scene.flat_normals.len() as u32)
            .map(|g| {
                let (o, s) = scene.locate(g);
                let mesh = &scene.objects[o].mesh;
                let x: Vec<Vector<N>> = mesh.simplices[s]
                    .iter()
                    .map(|&i| mesh.vertices[i as usize])
                    .collect();
                let mut m = [[0.0; N]; N];
                for (k, row) in m.iter_mut().enumerate() {
                    *row = if k + 1 < N {
                        sub(&x[k + 1], &x[0])
                    } else {
                        scene.camera.toward_eye(&x[0])
                    };
                }
                scene.render.cull_backfaces && det(&m) < 0.0
            })
            .collect();
        let accept = |g: u32| !culled[g as usize];
        let samples = scene.render.samples as usize;
        // Stale values in buffers of every output's size, which the trace takes from the pool
        // (unless a concurrent test does): it must overwrite every element.
        let cells = scene.camera.cell_count();
        for len in [cells * 4, cells, cells * N] {
            pool::recycle(vec![f32::NAN; len]);
        }
        pool::recycle(vec![7i32; cells]);
        pool::recycle(vec![7i64; cells]);
        let retina = trace(scene, &Progress::default()).unwrap();
        let (mut lit, mut shadowed) = (0, 0);
        for cell in 0..scene.camera.cell_count() {
            let (color, nearest, covered, blocked) = one_ray_at_a_time(scene, cell, &accept);
            let inv = 1.0 / samples as f64;
            for k in 0..3 {
                assert_eq!(
                    retina.rgba[cell * 4 + k].to_bits(),
                    ((color[k] * inv) as f32).to_bits(),
                    "N={N}, samples {samples}, cell {cell}, channel {k}"
                );
            }
            assert_eq!(retina.rgba[cell * 4 + 3], (covered as f64 * inv) as f32);
            // Every element written, misses' too, with the nearest hit's record.
            let normal = &retina.normal[cell * N..(cell + 1) * N];
            assert_eq!(
                retina.depth[cell].to_bits(),
                (nearest.depth as f32).to_bits()
            );
            assert_eq!(normal, nearest.normal.map(|x| x as f32).as_slice());
            assert_eq!(
                (retina.object_id[cell], retina.primitive_id[cell]),
                (nearest.object, nearest.primitive),
                "cell {cell}"
            );
            if covered > 0 {
                assert!(retina.object_id[cell] >= 0 && retina.primitive_id[cell] >= 0);
                assert!(retina.depth[cell].is_finite(), "cell {cell}");
                let len2: f32 = normal.iter().map(|x| x * x).sum();
                assert!((len2 - 1.0).abs() < 1e-5, "cell {cell}: normal {normal:?}");
            } else {
                assert_eq!(
                    (retina.object_id[cell], retina.primitive_id[cell]),
                    (-1, -1)
                );
                assert_eq!(retina.depth[cell], f32::INFINITY, "cell {cell}");
                assert!(normal.iter().all(|&x| x == 0.0), "cell {cell}: {normal:?}");
            }
            lit += (covered > 0) as usize;
            shadowed += (blocked > 0) as usize;
        }
        (lit, shadowed)
    }

    /// [`shade_as_one_ray_at_a_time`] on the scene `text`, which must have at least `lit` cells
    /// hit and at least `shadowed` with a blocked shadow ray.
    fn shades_as_one_ray_at_a_time(text: &str, lit: usize, shadowed: usize) {
        let (_, any) = load_toml_str(text, "test.toml", None).unwrap();
        let (l, s) = crate::with_scene!(&any, scene, _N => shade_as_one_ray_at_a_time(scene));
        assert!(
            l >= lit && s >= shadowed,
            "{l} cells hit, {s} in shadow, in\n{text}"
        );
    }

    /// Two point lights (one with falloff) and a directional one, for the 3D shading tests.
    const LIGHTS: &str = r#"
[[lights]]
type = "point"
position = [2.0, 3.0, 2.5]
color = [0.8, 0.7, 0.6]
[[lights]]
type = "directional"
direction = [-1.0, 0.5, 0.2]
color = [0.3, 0.4, 0.5]
[[lights]]
type = "point"
position = [-3.0, -0.5, 1.0]
color = [0.2, 0.2, 0.9]
falloff = 1.0"#;

    #[test]
    fn terms_added_at_once_or_after_the_shadow_pass_sum_in_light_order() {
        // One coarse smooth convex sphere: a term needs a shadow ray only when its light lies
        // on the inner side of the flat facet hit, which the smooth normal still faces (near
        // each light's terminator); that ray leaves through the inside and is blocked. So a
        // ray's terms are added at once, or some wait for the shadow pass (in at least one
        // cell); without shadows all are added at once.
        for (shadows, shadowed) in [(true, 1), (false, 0)] {
            let text = format!(
                r#"
dim = 3
ambient = [0.1, 0.1, 0.1]
[camera]
position = [0.0, 0.0, 4.0]
look_at = [0.0, 0.0, 0.0]
up = [[0.0, 1.0, 0.0]]
fov = 40.0
resolution = [40, 30]
{LIGHTS}
[[objects]]
shape = "sphere"
subdivisions = 1
material = {{ color = [0.9, 0.5, 0.3], specular = 0.5, shininess = 20.0, smooth = true }}
[render]
shadows = {shadows}
"#
            );
            shades_as_one_ray_at_a_time(&text, 300, shadowed);
        }
    }

    #[test]
    fn packets_shade_every_cell_as_one_ray_at_a_time() {
        // Objects that shadow each other, a light behind some surfaces (filtered out before the
        // shadow pass), two lights of each kind, 1 and 3 samples (packets split across cells).
        // Retinas in 8×8 tiles: 37 × 29 (one short chunk, partial tiles and strip), 64 × 70
        // (a full chunk of 64 rows and a short one of 6), 64 × 67 (the short chunk ends with a
        // strip of 3 rows, the last of them alone).
        for (samples, resolution) in [
            (1, "[37, 29]"),
            (3, "[37, 29]"),
            (1, "[64, 70]"),
            (3, "[64, 70]"),
            (1, "[64, 67]"),
        ] {
            let text = format!(
                r#"
dim = 3
ambient = [0.1, 0.1, 0.1]
[camera]
position = [0.5, 1.0, 6.0]
look_at = [0.0, 0.0, 0.0]
up = [[0.0, 1.0, 0.0]]
fov = 40.0
resolution = {resolution}
{LIGHTS}
[[objects]]
shape = "sphere"
subdivisions = 2
material = {{ color = [0.9, 0.5, 0.3], specular = 0.5, shininess = 20.0, smooth = true }}
[[objects]]
shape = "hypercube"
transform = [{{ scale = 0.4 }}, {{ translate = [1.0, 0.8, 1.2] }}]
[[objects]]
shape = "hypercube"
transform = [{{ scale = [3.0, 0.1, 3.0] }}, {{ translate = [0.0, -1.3, 0.0] }}]
[render]
samples = {samples}
seed = 5
shadows = true
"#
            );
            shades_as_one_ray_at_a_time(&text, 301, 51);
        }
        // A 3D retina in strips of rows, within slices (6 rows) and across them (5 rows), and
        // in two chunks, the second starting mid-slice (row 512: slice 7, row 22).
        for resolution in ["[8, 6, 5]", "[8, 5, 6]", "[8, 70, 10]"] {
            let text = format!(
                r#"
dim = 4
[camera]
position = [0.3, 0.5, 0.2, 2.6]
look_at = [0.0, 0.0, 0.0, 0.0]
up = [[0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0]]
fov = 60.0
resolution = {resolution}
[[lights]]
type = "point"
position = [2.0, 3.0, 1.0, 2.5]
[[objects]]
shape = "sphere"
subdivisions = 1
[[objects]]
shape = "hypercube"
transform = [{{ scale = 0.3 }}, {{ translate = [0.5, 0.6, 0.2, 1.2] }}]
[render]
shadows = true
"#
            );
            shades_as_one_ray_at_a_time(&text, 61, 6);
        }
    }

    #[test]
    fn other_cameras_and_dimensions_shade_as_one_ray_at_a_time() {
        // (scene, cells hit at least, cells with a blocked shadow ray at least), each traced
        // with 1, 2 and 3 samples per cell.
        let cases = [
            // N = 2: a 1-D retina of one chunk, a polygon circle shadowing a square.
            (
                r#"
dim = 2
[camera]
position = [0.3, 3.0]
look_at = [0.0, 0.0]
fov = 70.0
resolution = 53
[[lights]]
type = "point"
position = [2.5, 2.0]
[[lights]]
type = "directional"
direction = [-1.0, 0.3]
color = [0.3, 0.2, 0.1]
[[objects]]
shape = "sphere"
subdivisions = 3
material = { color = [0.9, 0.5, 0.3], specular = 0.5, shininess = 8.0 }
[[objects]]
shape = "hypercube"
transform = [{ scale = 0.3 }, { translate = [-1.2, -0.6] }]
[render]
shadows = true
samples = SAMPLES
"#,
                15,
                1,
            ),
            // Orthographic, one-sided lighting, back-face culling: a triangle facing the camera
            // and one facing away (culled: the sphere behind it shows).
            (
                r#"
dim = 3
[camera]
position = [0.2, 0.1, 5.0]
look_at = [0.0, 0.0, 0.0]
up = [[0.0, 1.0, 0.0]]
projection = "orthographic"
extent = 2.0
resolution = [30, 21]
[[lights]]
type = "point"
position = [1.0, 3.0, 4.0]
falloff = 2.0
[[objects]]
shape = "sphere"
subdivisions = 2
[[objects]]
shape = "mesh"
vertices = [[-1.9, -1.9, 2.0], [-0.7, -1.9, 2.0], [-1.9, -0.7, 2.0],
            [0.0, 0.0, 1.6], [0.0, 1.2, 1.6], [1.2, 0.0, 1.6]]
simplices = [[0, 1, 2], [3, 4, 5]]
[render]
shadows = true
cull_backfaces = true
two_sided = false
samples = SAMPLES
"#,
                150,
                20,
            ),
            // One cell.
            (
                r#"
dim = 3
[camera]
position = [0.0, 0.0, 3.0]
look_at = [0.0, 0.0, 0.0]
up = [[0.0, 1.0, 0.0]]
fov = 10.0
resolution = 1
[[lights]]
type = "directional"
direction = [0.2, 0.3, 1.0]
[[objects]]
shape = "sphere"
subdivisions = 1
[render]
samples = SAMPLES
"#,
                1,
                0,
            ),
            // N = 4, orthographic, a retina of unequal sides with a side of 1.
            (
                r#"
dim = 4
[camera]
position = [0.3, 0.2, 0.1, 4.0]
look_at = [0.0, 0.0, 0.0, 0.0]
up = [[0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0]]
projection = "orthographic"
extent = 1.5
resolution = [5, 7, 1]
[[lights]]
type = "point"
position = [1.0, 2.0, 0.5, 3.0]
[[objects]]
shape = "hypercube"
transform = [{ rotate = { plane = [0, 3], degrees = 20.0 } }]
[render]
shadows = true
samples = SAMPLES
"#,
                12,
                0,
            ),
            // N = 5 and N = 7, perspective, with shadows between two objects.
            (
                r#"
dim = 5
[camera]
position = [0.2, 0.3, 0.1, 0.4, 3.0]
look_at = [0.0, 0.0, 0.0, 0.0, 0.0]
up = [[0.0, 1.0, 0.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0, 0.0]]
fov = 45.0
resolution = 8
[[lights]]
type = "point"
position = [1.0, 2.0, 0.5, 0.3, 2.5]
[[objects]]
shape = "sphere"
subdivisions = 1
[[objects]]
shape = "cross_polytope"
transform = [{ scale = 0.6 }, { translate = [0.65, 1.3, 0.32, 0.19, 1.6] }]
[render]
shadows = true
samples = SAMPLES
"#,
                300,
                200,
            ),
            (
                r#"
dim = 7
[camera]
position = [0.1, 0.2, 0.1, 0.1, 0.1, 0.1, 3.0]
look_at = [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]
up = [[0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0],
      [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0], [0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0],
      [0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0]]
fov = 50.0
resolution = 3
[[lights]]
type = "directional"
direction = [0.3, 1.0, 0.2, 0.1, 0.0, 0.2, 1.0]
[[objects]]
shape = "hypercube"
[render]
samples = SAMPLES
"#,
                700,
                0,
            ),
        ];
        for (text, lit, shadowed) in cases {
            for samples in [1, 2, 3] {
                let text = text.replace("SAMPLES", &samples.to_string());
                shades_as_one_ray_at_a_time(&text, lit, shadowed);
            }
        }
    }

    #[test]
    fn tile_order_covers_each_cell_once_in_compact_packets() {
        assert_eq!(chunking(37, 1), (CHUNK, false));
        assert_eq!(chunking(512, 2), (4096, true));
        assert_eq!(chunking(128, 3), (4096, true));
        assert_eq!(chunking(100, 2), (4800, true));
        assert_eq!(chunking(2048, 2), (16384, true));
        assert_eq!(chunking(3000, 2), (CHUNK, false));
        for (row, rows) in [
            (512, 8),
            (128, 32),
            (100, 48),
            (37, 13),
            (8, 6),
            (5, 1),
            (1, 7),
        ] {
            let order = tile_order(row, rows);
            let mut seen = vec![false; row * rows];
            for &(cell, r, c) in &order {
                assert_eq!(cell as usize, r as usize * row + c as usize);
                assert!(
                    !std::mem::replace(&mut seen[cell as usize], true),
                    "{row}×{rows}"
                );
            }
            assert!(seen.iter().all(|&s| s), "{row}×{rows}");
            // Where rows and columns divide evenly, every packet is 4 columns × 2 rows and every
            // 64 slots fill one 8×8 tile.
            if row.is_multiple_of(TILE) && rows.is_multiple_of(TILE) {
                for p in order.chunks(PACKET) {
                    let (r, c) = (p[0].1, p[0].2);
                    assert!(r % 2 == 0 && c % 4 == 0, "{row}×{rows}");
                    for (k, &(_, rk, ck)) in p.iter().enumerate() {
                        assert_eq!((rk, ck), (r + k as u32 / 4, c + k as u32 % 4));
                    }
                }
                for tile in order.chunks(TILE * TILE) {
                    let (r, c) = (tile[0].1 / 8 * 8, tile[0].2 / 8 * 8);
                    assert!(tile
                        .iter()
                        .all(|&(_, rk, ck)| rk - r < 8 && ck >= c && ck - c < 8));
                }
            }
        }
    }

    /// Shadow rays that skip the convex object they leave change nothing: the retina is the
    /// same, bit for bit, when every object's convexity certificate is dropped (so that every
    /// shadow ray is tested against everything).
    fn skipping_convex_objects_changes_nothing<const N: usize>(scene: &mut Scene<N>) -> usize {
        let fast = trace(scene, &Progress::default()).unwrap();
        let convex = scene.objects.iter().filter(|o| o.convex.is_some()).count();
        scene.objects.iter_mut().for_each(|o| o.convex = None);
        let slow = trace(scene, &Progress::default()).unwrap();
        assert!(fast
            .rgba
            .iter()
            .zip(&slow.rgba)
            .all(|(a, b)| a.to_bits() == b.to_bits()));
        assert_eq!(fast, slow);
        convex
    }

    #[test]
    fn shadow_rays_skipping_convex_objects_give_the_same_image() {
        // Convex objects that shadow each other, a light inside one of them, each kind of
        // light, and a non-convex lattice sphere, all in a convex room with the camera: the
        // shadow rays from its walls toward the directional light leave on the inner side and
        // are blocked by the room itself.
        for (dim, extra) in [(3, ""), (4, ", 0.3"), (5, ", 0.3, -0.2")] {
            let up: Vec<String> = (1..dim - 1)
                .map(|k| {
                    let e: Vec<&str> = (0..dim)
                        .map(|i| if i == k { "1.0" } else { "0.0" })
                        .collect();
                    format!("[{}]", e.join(", "))
                })
                .collect();
            let z = ", 0.0".repeat(dim - 3);
            let text = format!(
                r#"
dim = {dim}
ambient = [0.1, 0.1, 0.1]
[camera]
position = [0.5, 1.0, 6.0{extra}]
look_at = [0.0, 0.0, 0.0{z}]
up = [{up}]
fov = 50.0
resolution = 24
[[lights]]
type = "point"
position = [2.0, 3.0, 2.5{z}]
[[lights]]
type = "directional"
direction = [-1.0, 0.5, 0.2{extra}]
[[lights]]
type = "point"
position = [-0.6, 0.2, 0.4{z}]
color = [0.5, 0.2, 0.2]
[[objects]]
shape = "cross_polytope"
transform = [{{ scale = 0.8 }}, {{ translate = [-0.6, 0.2, 0.4{z}] }}]
[[objects]]
shape = "simplex"
transform = [{{ scale = 0.5 }}, {{ translate = [0.9, 0.8, 1.2{z}] }}]
[[objects]]
shape = "hypercube"
transform = [{{ scale = 7.0 }}]
material = {{ smooth = true }}
[[objects]]
shape = "sphere"
subdivisions = 1
transform = [{{ scale = 0.4 }}, {{ translate = [1.0, -0.6, -0.5{z}] }}]
[render]
shadows = true
two_sided = true
"#,
                up = up.join(", ")
            );
            let (_, mut any) = load_toml_str(&text, "test.toml", None).unwrap();
            let convex = crate::with_scene!(&mut any, scene, _N => skipping_convex_objects_changes_nothing(scene));
            assert_eq!(
                convex, 3,
                "N={dim}: the polytopes are convex, the sphere is not"
            );
        }
        // One convex object alone, lit from outside: its shadow rays are not traced at all.
        for dim in [3, 4] {
            let z = ", 0.0".repeat(dim - 3);
            let up = if dim == 3 {
                "[[0.0, 1.0, 0.0]]"
            } else {
                "[[0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0]]"
            };
            let text = format!(
                r#"
dim = {dim}
[camera]
position = [0.5, 1.0, 4.0{z}]
look_at = [0.0, 0.0, 0.0{z}]
up = {up}
fov = 50.0
resolution = 16
[[lights]]
type = "point"
position = [2.0, 3.0, 2.5{z}]
[[objects]]
shape = "cross_polytope"
transform = [{{ rotate = {{ plane = [0, 2], degrees = 20.0 }} }}]
[render]
shadows = true
"#
            );
            let (_, mut any) = load_toml_str(&text, "test.toml", None).unwrap();
            let convex = crate::with_scene!(&mut any, scene, _N => skipping_convex_objects_changes_nothing(scene));
            assert_eq!(convex, 1, "N={dim}");
        }
    }

    #[test]
    fn latin_hypercube_offsets_stratify_every_axis() {
        let mut rng = SplitMix::new(7, 3);
        let mut out = vec![];
        sample_offsets(16, 3, &mut rng, &mut out);
        for k in 0..3 {
            let mut strata: Vec<usize> =
                (0..16).map(|j| (out[j * 3 + k] * 16.0) as usize).collect();
            strata.sort();
            assert_eq!(strata, (0..16).collect::<Vec<_>>());
        }
        sample_offsets(1, 3, &mut rng, &mut out);
        assert_eq!(out, vec![0.5; 3]);
    }
}
