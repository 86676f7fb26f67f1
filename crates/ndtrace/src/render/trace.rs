//! [`trace`]: the retina, chunk by chunk in parallel, each chunk group by group, each cell's
//! value from its rays; [`trace_slab`]: the same for a run of whole chunks (a slab of the
//! retina traced elsewhere, e.g. on a Dask worker), with the same bits for each cell.

use super::packets::{GroupTracer, ObjectShading};
use super::pool;
use super::sampling::{sample_offsets, SplitMix};
use super::shade::depth_range;
use super::tiles::{chunking, tile_order};
use super::{NearestHit, Progress, Retina};
use crate::accel::{prefetch_of, PACKET};
use crate::camera::CentreRays;
use crate::scene::desc::RenderMode;
use crate::scene::Scene;
use crate::{NdError, NdResult};
use rayon::prelude::*;
use std::ops::Range;
use std::sync::atomic::Ordering;

/// Traces every retina cell of `scene` (on the current rayon pool), then projects its surface
/// objects into the retina (`render/splat.rs`).
pub fn trace<const N: usize>(scene: &Scene<N>, progress: &Progress) -> NdResult<Retina> {
    let mut retina = trace_cells(scene, progress, 0..scene.camera.cell_count())?;
    retina.shape = scene.camera.numpy_shape();
    Ok(retina)
}

/// The retina cells `cells` of `scene` (a range of cell indices in memory order, from
/// [`slabs`]: whole chunks of the tracing order), each with the bits [`trace`] gives it. The
/// result is flat: its `shape` is `[cells.len()]`. Concatenating the slabs of [`slabs`] in
/// order gives [`trace`]'s retina.
pub fn trace_slab<const N: usize>(
    scene: &Scene<N>,
    progress: &Progress,
    cells: Range<usize>,
) -> NdResult<Retina> {
    let cam = &scene.camera;
    let (chunk, _) = chunking(cam.resolution[0], N - 1);
    let total = cam.cell_count();
    if cells.start > cells.end
        || cells.end > total
        || !cells.start.is_multiple_of(chunk)
        || (!cells.end.is_multiple_of(chunk) && cells.end != total)
    {
        return Err(NdError::Value {
            arg: "cells".into(),
            message: format!(
                "expected a slab of whole chunks of {chunk} cells within 0..{total} \
                 (from the scene's slabs), got {}..{}",
                cells.start, cells.end
            ),
        });
    }
    trace_cells(scene, progress, cells)
}

/// The cut of the retina of `scene` into `count` slabs of whole chunks (at most one per
/// chunk, at least one), as even as chunks allow, in order: cell ranges for [`trace_slab`].
pub fn slabs<const N: usize>(scene: &Scene<N>, count: usize) -> Vec<Range<usize>> {
    let cam = &scene.camera;
    let (chunk, _) = chunking(cam.resolution[0], N - 1);
    let total = cam.cell_count();
    let chunks = total.div_ceil(chunk);
    let count = count.clamp(1, chunks.max(1));
    (0..count)
        .map(|k| {
            let (a, b) = (chunks * k / count, chunks * (k + 1) / count);
            (a * chunk).min(total)..(b * chunk).min(total)
        })
        .collect()
}

/// [`trace_slab`] without the check: culling, the cells' rays, then the surfaces' fragments
/// that fall on those cells.
fn trace_cells<const N: usize>(
    scene: &Scene<N>,
    progress: &Progress,
    cells: Range<usize>,
) -> NdResult<Retina> {
    // Back-face culling (course notes): discard a simplex when det[x_1−x_0 … | C − x_0] < 0,
    // i.e. when its normal points away from the eye. The eye is fixed per trace.
    // One `accept` with culling and without (no list culls nothing): the trace, most of the
    // code compiled per N, is instantiated once per closure type. `accept` runs only on a hit
    // nearer than the best so far.
    let culled = match scene.render.cull_backfaces {
        true => scene.backfaces(),
        false => Vec::new(),
    };
    trace_accepting(scene, progress, cells.clone(), |id| {
        culled.is_empty() || !culled[id as usize]
    })
    .and_then(|mut retina| {
        // Surfaces ("bear hair"), projected over what the rays saw.
        super::splat::splat(scene, &mut retina, cells.start, progress)?;
        Ok(retina)
    })
}

/// The cells `cells` (whole chunks) with camera rays that see only the simplices whose
/// global id passes `accept`.
fn trace_accepting<const N: usize, F>(
    scene: &Scene<N>,
    progress: &Progress,
    range: Range<usize>,
    accept: F,
) -> NdResult<Retina>
where
    F: Fn(u32) -> bool + Sync,
{
    let cam = &scene.camera;
    let cells = range.len();
    // Kept buffers when the last retina's were handed back ([`pool`]), not cleared: the loop
    // writes every element of every cell, misses included.
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
    // The slab's first chunk (a whole number of chunks from the retina's start).
    let first_chunk = range.start / chunk_cells;
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
            |(local, ((((rgba, depth), normal), object_id), primitive_id))| {
                let chunk = first_chunk + local;
                if progress.cancel.load(Ordering::Relaxed) {
                    return;
                }
                let mut group_tracer = GroupTracer::default();
                let mut offsets = Vec::with_capacity(samples * (N - 1));
                let mut u = [0.0; N];
                let mut idx = [0; N];
                cam.cell_index(chunk * chunk_cells, &mut idx);
                // 1. The order of the chunk's cells: tiled when the chunks are whole rows, with
                //    the multi-index of the first cell of each row of the chunk.
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
                    // 2. The rays of a group of cells: slots of the processing order, and the
                    //    chunk's cell in each.
                    let slots = first..(first + group).min(len);
                    let cell_of = |s: usize| tiled.map_or(s, |t| t[s].0 as usize);
                    group_tracer.rays.clear();
                    for s in slots.clone() {
                        let c = cell_of(s);
                        // The cell's entries are written after the group's trace: ask for
                        // their lines now, so that those stores do not wait for memory (a
                        // tile's row writes a few bytes in each row of a 100 MB retina).
                        prefetch_of(&rgba[c * 4]);
                        prefetch_of(&depth[c]);
                        prefetch_of(&normal[c * N]);
                        prefetch_of(&object_id[c]);
                        prefetch_of(&primitive_id[c]);
                        if let Some(t) = tiled {
                            let (_, r, col) = t[s];
                            idx = rows[r as usize];
                            idx[0] = col as usize;
                        }
                        if samples == 1 {
                            group_tracer.rays.push(centre.ray(&idx));
                        } else {
                            let cell = chunk * chunk_cells + c;
                            let mut rng = SplitMix::new(scene.render.seed, cell as u64);
                            sample_offsets(samples, N - 1, &mut rng, &mut offsets);
                            for f in offsets.chunks(N - 1) {
                                cam.cell_point(&idx, f, &mut u);
                                group_tracer.rays.push(cam.ray(&u[..N - 1]));
                            }
                        }
                        if tiled.is_none() {
                            cam.next_cell(&mut idx);
                        }
                    }
                    // 3. Their nearest hits and colours.
                    let any = group_tracer.trace_and_shade(scene, &accept, &shading, depth_range);
                    if !any {
                        // Every ray missed: each cell holds the value of a miss (`cell_value`).
                        for s in slots {
                            let c = cell_of(s);
                            rgba[c * 4..c * 4 + 4].fill(0.0);
                            depth[c] = NearestHit::<N>::MISS.depth as f32;
                            normal[c * N..(c + 1) * N].fill(0.0);
                            object_id[c] = NearestHit::<N>::MISS.object;
                            primitive_id[c] = NearestHit::<N>::MISS.primitive;
                        }
                        continue;
                    }
                    // 4. Each cell's value from its rays, into the retina.
                    for (j, s) in slots.enumerate() {
                        let c = cell_of(s);
                        let (px, nearest) =
                            cell_value(&group_tracer.color, &group_tracer.nearest, j, samples);
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
        shape: vec![cells],
        rgba,
        depth,
        normal,
        object_id,
        primitive_id,
    })
}

/// The value of the `j`-th cell of a group from its `samples` rays (rays `j·samples …` of
/// `colors` and `hits`): premultiplied RGBA, the mean of their colours (misses' are 0) and the
/// fraction that hit, and the nearest hit ([`NearestHit::MISS`] if none; the first sample of
/// least depth).
#[inline(always)]
fn cell_value<'a, const N: usize>(
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
