//! The 3D views of a retina (N ≥ 4): the volume (or the illustrative cues) prepared once, then
//! seen through any number of compositing cameras — one picture, a stereo pair, the sections
//! layout, the frames of a turntable — with the feature edges drawn over each view.

use super::aids::{cut, world_of, Cutaway, ViewLayout};
use super::annotate::{hull, PictureLayout, Rect};
use super::illustrative::{self, Cues3};
use super::montage::{render_tiles, Tiles};
use super::overlay::{self, PixelEdge, RetinaEdge};
use super::picture::Exact;
use super::stages::{project_stage, stage_params, stage_point};
use super::volume::{occupied_box, render_view, Camera3, Grid};
use super::{prepare, CompositeMode, CompositeOptions, Detail, RetinaExtras, Volume};
use crate::camera::Projection;
use glam::DVec3;

/// What the views are rendered from.
enum Source {
    /// A premultiplied volume (volume, mip and first-hit modes).
    Grid(Grid),
    /// The illustrative cues of a 3D retina (or, for N ≥ 5, of the stages' 3D volume),
    /// classified per view.
    Cues(Cues3),
}

/// A piece of a feature edge in the 3D volume's cell coordinates.
struct Edge3 {
    a: DVec3,
    b: DVec3,
    depth: [f64; 2],
    visible: bool,
    color: [f32; 3],
}

/// A retina of m ≥ 3 axes made ready for 3D views.
pub(super) struct View3<'a> {
    /// Drawn at the picture's resolution from the retina's scene ([`Detail::Scene`]), when it
    /// comes with one; else (and for the modes that do not) from `source`.
    exact: Option<Exact<'a>>,
    source: Source,
    /// Cells of the 3D volume (column, row, slice).
    n: [usize; 3],
    /// The box the camera frames, when `fit`: about the occupied cells' centre, with the
    /// radius of their [`hull`](super::annotate::Hull) as its half-diagonal.
    frame: Option<([f64; 3], [f64; 3])>,
    /// When `fit`, the corners of the occupied part the views centre in their panels.
    hull: Vec<DVec3>,
    /// For the sections layout: the premultiplied 3D volume (before any cutaway).
    sections: Option<Volume>,
    /// With `fit`, the cells (column, row, slice; lower and upper bounds) the sections show:
    /// the box of the occupied ones and a cell around, so each section frames the object.
    section_box: Option<([usize; 3], [usize; 3])>,
    edges: Vec<Edge3>,
    /// The mode the views are marched in.
    mode: CompositeMode,
}

impl<'a> View3<'a> {
    pub(super) fn new(
        rgba: &[f32],
        depth: Option<&'a [f32]>,
        shape: &[usize],
        extras: &RetinaExtras<'a>,
        cells: usize,
        opts: &CompositeOptions,
    ) -> Self {
        if let Some(probe) = extras.scene {
            let exact_modes = matches!(
                opts.mode,
                CompositeMode::FirstHit | CompositeMode::Volume | CompositeMode::Illustrative
            );
            if shape.len() == 3
                && opts.detail == Detail::Scene
                && exact_modes
                && opts.cubes.is_none()
            {
                return Self::exact(probe, rgba, depth, shape, extras, cells, opts);
            }
        }
        let ortho = opts.projection == Projection::Orthographic;
        let down_to_3d = |mut vol: Volume| {
            let mut stage = 0;
            while vol.shape.len() > 3 {
                let (f, d) = stage_params(&vol.shape, opts.stages.get(stage).copied());
                vol = project_stage(&vol, f, d, ortho);
                stage += 1;
            }
            vol
        };
        let n = [
            shape[shape.len() - 1],
            shape[shape.len() - 2],
            shape[shape.len() - 3],
        ];
        let plain = || {
            down_to_3d(Volume {
                shape: shape.to_vec(),
                cells: prepare(rgba, depth, cells, opts),
            })
        };
        let sections = (opts.layout == ViewLayout::Sections).then(plain);
        // Cubes draw the cells themselves, whatever the mode.
        let illustrative = opts.mode == CompositeMode::Illustrative && opts.cubes.is_none();
        // The framing box: the occupied cells before any cutaway, so a cut does not move the
        // object in the picture.
        let mut frame = None;
        let mut occupied = None;
        let source = if illustrative {
            // The cells' colours with the depth cue (coverage unscaled: `opacity` scales the
            // interior).
            let unit = CompositeOptions {
                opacity: 1.0,
                ..opts.clone()
            };
            let mut prepared = prepare(rgba, depth, cells, &unit);
            if shape.len() == 3 {
                frame = box_of(shape, &prepared);
                occupied = opts.fit.then(|| hull(shape, &prepared)).flatten();
                if let Some(c) = &opts.cutaway {
                    cut(&mut prepared, shape, c);
                }
            }
            let hits: Vec<f32>;
            let depth = match depth {
                Some(d) => d,
                None => {
                    hits = (0..cells)
                        .map(|i| {
                            if rgba[i * 4 + 3] > 0.0 {
                                1.0
                            } else {
                                f32::INFINITY
                            }
                        })
                        .collect();
                    &hits
                }
            };
            let camera = extras.camera.as_ref();
            if shape.len() == 3 {
                // The cues of the cells within their reach of the hit ones (the box of the
                // occupied cells, grown): the same cues as over the whole retina.
                let full = [shape[0], shape[1], shape[2]];
                let (lo, m) = match frame {
                    Some((a, b)) => {
                        let lo: [usize; 3] = std::array::from_fn(|k| {
                            (a[2 - k] as usize).saturating_sub(illustrative::CUE_REACH)
                        });
                        let m: [usize; 3] = std::array::from_fn(|k| {
                            (b[2 - k] as usize + illustrative::CUE_REACH).min(full[k]) - lo[k]
                        });
                        (lo, m)
                    }
                    None => ([0; 3], full),
                };
                let prepared: Vec<f32> = window(&prepared, 1, full, lo, m)
                    .into_iter()
                    .flatten()
                    .collect();
                let depth = window(depth, 1, full, lo, m);
                let normal = extras.normal.map(|nrm| window(nrm, 4, full, lo, m));
                Source::Cues(Cues3::new(
                    &prepared,
                    &depth,
                    normal.as_deref(),
                    &m,
                    illustrative::Window {
                        origin: &lo,
                        full: &full,
                    },
                    camera,
                    opts,
                ))
            } else {
                let prepared: Vec<f32> = prepared.into_iter().flatten().collect();
                let (classified, coverage) =
                    illustrative::classify(&prepared, depth, extras.normal, shape, camera, opts);
                let mut vol = down_to_3d(Volume {
                    shape: shape.to_vec(),
                    cells: classified,
                });
                let mut coverage = down_to_3d(Volume {
                    shape: shape.to_vec(),
                    cells: coverage,
                });
                frame = box_of(&vol.shape, &vol.cells);
                occupied = opts.fit.then(|| hull(&vol.shape, &vol.cells)).flatten();
                if let Some(c) = &opts.cutaway {
                    cut(&mut vol.cells, &vol.shape, c);
                    cut(&mut coverage.cells, &coverage.shape, c);
                }
                Source::Cues(Cues3::projected(&vol, &coverage, opts))
            }
        } else {
            let mut vol = plain();
            frame = box_of(&vol.shape, &vol.cells);
            occupied = opts.fit.then(|| hull(&vol.shape, &vol.cells)).flatten();
            if let Some(c) = &opts.cutaway {
                cut(&mut vol.cells, &vol.shape, c);
            }
            Source::Grid(Grid::new(&vol))
        };
        let section_box = (sections.as_ref())
            .filter(|_| opts.fit)
            .and_then(|v| box_of(&v.shape, &v.cells))
            .map(|(lo, hi)| {
                let full = [
                    v_dims(&sections, 2),
                    v_dims(&sections, 1),
                    v_dims(&sections, 0),
                ];
                (
                    lo.map(|x| (x as usize).saturating_sub(1)),
                    std::array::from_fn(|k| (hi[k] as usize + 1).min(full[k])),
                )
            });
        let (frame, hull) = match (opts.fit, occupied) {
            (true, Some(h)) => (Some(h.frame), h.points),
            (true, None) => (frame, Vec::new()),
            (false, _) => (None, Vec::new()),
        };
        let edges = if illustrative && opts.edges {
            edges_3d(extras.edges, shape, n, opts)
        } else {
            Vec::new()
        };
        View3 {
            exact: None,
            source,
            n,
            frame,
            hull,
            sections,
            section_box,
            edges,
            mode: if illustrative {
                CompositeMode::Volume
            } else {
                opts.mode
            },
        }
    }

    /// The views of a 3D retina drawn from its scene ([`Exact`]): the structure and the cells'
    /// colours, framed by the structure's hull (the same at any retina resolution).
    fn exact(
        probe: &'a dyn super::probe::SceneProbe,
        rgba: &[f32],
        depth: Option<&'a [f32]>,
        shape: &[usize],
        extras: &RetinaExtras<'a>,
        cells: usize,
        opts: &CompositeOptions,
    ) -> Self {
        let unit = CompositeOptions {
            opacity: 1.0,
            ..opts.clone()
        };
        let prepared = prepare(rgba, depth, cells, &unit);
        let exact = Exact::new(probe, &prepared, shape, depth, extras.object, opts);
        let n = [shape[2], shape[1], shape[0]];
        let (frame, hull) = match exact.hull().filter(|_| opts.fit) {
            Some(h) => (Some(h.frame), h.points),
            None => (None, Vec::new()),
        };
        let illustrative = opts.mode == CompositeMode::Illustrative;
        let edges = if illustrative && opts.edges {
            edges_3d(extras.edges, shape, n, opts)
        } else {
            Vec::new()
        };
        // What a camera the structure cannot be projected for sees: the cells, opaque where
        // the first-hit surface is.
        let source = Source::Grid(Grid::new(&Volume {
            shape: shape.to_vec(),
            cells: prepared,
        }));
        View3 {
            exact: Some(exact),
            source,
            n,
            frame,
            hull,
            sections: None,
            section_box: None,
            edges,
            mode: opts.mode,
        }
    }

    /// The picture of `opts` (its azimuth and layout) with the panels of `layout`.
    pub(super) fn picture(&self, opts: &CompositeOptions, layout: &PictureLayout) -> Vec<f32> {
        let (w, h) = layout.size;
        let bg = opts.background.map(|x| x as f32);
        let sized = |r: Rect, azimuth: f64| CompositeOptions {
            size: (r.w.max(1), r.h.max(1)),
            azimuth,
            ..opts.clone()
        };
        let first = layout.panels[0].rect;
        if layout.panels.len() == 1 && (first.w, first.h) == (w, h) {
            return self.view(&sized(first, opts.azimuth));
        }
        let mut img = [bg[0], bg[1], bg[2], 0.0].repeat(w * h);
        let mut place = |r: Rect, tile: &[f32]| {
            if r.w > 0 && r.h > 0 {
                paste(&mut img, w, tile, r.w, r.x, r.y, r.w, r.h);
            }
        };
        match opts.layout {
            ViewLayout::Single => place(first, &self.view(&sized(first, opts.azimuth))),
            ViewLayout::Stereo => {
                let half = opts.stereo_angle / 2.0;
                for (panel, side) in layout.panels.iter().zip([-half, half]) {
                    let r = panel.rect;
                    place(r, &self.view(&sized(r, opts.azimuth + side)));
                }
            }
            // The slice's half is drawn by whoever traces the slice.
            ViewLayout::Slice => place(first, &self.view(&sized(first, opts.azimuth))),
            ViewLayout::Sections => {
                place(first, &self.view(&sized(first, opts.azimuth)));
                for (k, panel) in layout.panels.iter().skip(1).enumerate() {
                    let r = panel.rect;
                    if r.w > 0 && r.h > 0 {
                        let tile = match (&self.exact, &self.sections) {
                            (Some(ex), _) => ex.section(opts.section, k, r.w, r.h, opts),
                            (None, Some(vol)) => {
                                section(vol, opts.section, k, (r.w, r.h), self.section_box, bg)
                            }
                            (None, None) => unreachable!("a sections layout keeps its volume"),
                        };
                        place(r, &tile);
                    }
                }
            }
        }
        img
    }

    /// The feature-edge pieces of the view of `opts` in the first panel of `layout`, in the
    /// picture's pixels.
    pub(super) fn pixel_edges(
        &self,
        opts: &CompositeOptions,
        layout: &PictureLayout,
    ) -> Vec<PixelEdge> {
        let r = layout.panels[0].rect;
        let o = CompositeOptions {
            size: (r.w.max(1), r.h.max(1)),
            ..opts.clone()
        };
        let mut pieces = project(&self.edges, &self.camera(&o));
        for e in &mut pieces {
            for p in &mut e.p {
                p[0] += r.x as f64;
                p[1] += r.y as f64;
            }
        }
        pieces
    }

    /// The compositing camera of a view at `opts.size`: framing the occupied part's sphere and
    /// centring its projection (with `fit`), or the whole volume.
    fn camera(&self, opts: &CompositeOptions) -> Camera3 {
        let cam = Camera3::new(self.n, self.frame, opts);
        if self.hull.is_empty() {
            cam
        } else {
            cam.centred_on(&self.hull)
        }
    }

    /// One view at `opts.size`.
    fn view(&self, opts: &CompositeOptions) -> Vec<f32> {
        let bg = opts.background.map(|x| x as f32);
        let cam = self.camera(opts);
        if let Some(ex) = &self.exact {
            if let Some((mut img, half, cover)) = ex.view(&cam, self.mode, opts) {
                let mut pixels = project(&self.edges, &cam);
                if self.mode == CompositeMode::Illustrative && opts.edges {
                    let alpha: Vec<f32> = img.iter().skip(3).step_by(4).copied().collect();
                    let outline: Vec<Edge3> = ex
                        .silhouettes(&cam, &alpha)
                        .into_iter()
                        .map(|(a, b, depth)| Edge3 {
                            a,
                            b,
                            depth,
                            visible: true,
                            color: overlay::edge_color(opts),
                        })
                        .collect();
                    pixels.extend(project(&outline, &cam));
                }
                if !pixels.is_empty() {
                    let under = img.clone();
                    overlay::draw(&mut img, opts.size.0, &pixels, Some(&half), opts);
                    // The lines end at the object's outline, where its coverage does: nothing
                    // is drawn beyond it (a line on the silhouette shows its inner half).
                    for (i, &c) in cover.iter().enumerate() {
                        if c < 1.0 {
                            for k in i * 4..i * 4 + 4 {
                                img[k] = under[k] + (img[k] - under[k]) * c;
                            }
                        }
                    }
                }
                return img;
            }
            // The structure cannot be projected for this camera: the cells' picture.
            let mode = match self.mode {
                CompositeMode::Illustrative => CompositeMode::Volume,
                m => m,
            };
            let Source::Grid(grid) = &self.source else {
                unreachable!("an exact view keeps its cells as a grid")
            };
            let (mut img, half) = render_view(grid, &cam, mode, opts, bg, !self.edges.is_empty());
            if !self.edges.is_empty() {
                let pixels = project(&self.edges, &cam);
                overlay::draw(&mut img, opts.size.0, &pixels, half.as_deref(), opts);
            }
            return img;
        }
        let classified;
        let grid = match &self.source {
            Source::Grid(g) => g,
            Source::Cues(c) => {
                classified = Grid::placed(&c.classify(&cam), c.origin(), self.n);
                &classified
            }
        };
        let (mut img, half) = match opts.cubes {
            Some(c) => {
                super::cubes::render_cubes(grid, &cam, opts, c.size, bg, !self.edges.is_empty())
            }
            None => render_view(grid, &cam, self.mode, opts, bg, !self.edges.is_empty()),
        };
        if !self.edges.is_empty() {
            let pixels = project(&self.edges, &cam);
            overlay::draw(&mut img, opts.size.0, &pixels, half.as_deref(), opts);
        }
        img
    }
}

/// The cells `lo .. lo + m` (numpy order, `width` values per cell) of a 3D array of `shape`
/// cells.
fn window<T: Copy>(
    data: &[T],
    width: usize,
    shape: [usize; 3],
    lo: [usize; 3],
    m: [usize; 3],
) -> Vec<T> {
    let mut out = Vec::with_capacity(m.iter().product::<usize>() * width);
    for z in lo[0]..lo[0] + m[0] {
        for y in lo[1]..lo[1] + m[1] {
            let row = (z * shape[1] + y) * shape[2] + lo[2];
            out.extend_from_slice(&data[row * width..(row + m[2]) * width]);
        }
    }
    out
}

/// The box, in cell coordinates, of the cells with alpha > 0 of a 3D volume in numpy order.
fn box_of(shape: &[usize], cells: &[[f32; 4]]) -> Option<([f64; 3], [f64; 3])> {
    let (nx, ny) = (shape[2], shape[1]);
    occupied_box([nx, ny, shape[0]], |x, y, z| {
        cells[x + nx * (y + ny * z)][3]
    })
}

/// Copies a `qw` × `qh` block from `src` (`src_w` wide) into `dst` (`w` wide) at (x0, y0).
#[allow(clippy::too_many_arguments)]
fn paste(
    dst: &mut [f32],
    w: usize,
    src: &[f32],
    src_w: usize,
    x0: usize,
    y0: usize,
    qw: usize,
    qh: usize,
) {
    for y in 0..qh {
        let s = &src[y * src_w * 4..][..qw * 4];
        dst[((y0 + y) * w + x0) * 4..][..qw * 4].copy_from_slice(s);
    }
}

/// Axis `k` (numpy order) of the sections volume's shape.
fn v_dims(v: &Option<Volume>, k: usize) -> usize {
    v.as_ref().map_or(1, |v| v.shape[k])
}

/// Section `k` (0: across z, 1: across x, 2: across y; see [`ViewLayout::Sections`]) of the
/// volume through the world point `at`, its cells within `within` (column, row, slice bounds;
/// all of them when `None`), scaled to fit `w` × `h` over `bg`.
fn section(
    vol: &Volume,
    at: [f64; 3],
    k: usize,
    (w, h): (usize, usize),
    within: Option<([usize; 3], [usize; 3])>,
    bg: [f32; 3],
) -> Vec<f32> {
    let [nz, ny, nx] = [vol.shape[0], vol.shape[1], vol.shape[2]];
    let c = 2.0 / nx.max(ny).max(nz) as f64;
    let index = |v: f64, r: usize| ((v / c).floor().max(0.0) as usize).min(r - 1);
    let x0 = index(at[0] + nx as f64 * c / 2.0, nx);
    let y0 = index(ny as f64 * c / 2.0 - at[1], ny);
    let z0 = index(at[2] + nz as f64 * c / 2.0, nz);
    let idx = move |x: usize, y: usize, z: usize| x + nx * (y + ny * z);
    let (lo, hi) = within.unwrap_or(([0; 3], [nx, ny, nz]));
    let span = |a: usize| hi[a].saturating_sub(lo[a]).max(1);
    let (tw, th) = match k {
        0 => (span(0), span(1)),
        1 => (span(2), span(1)),
        _ => (span(0), span(2)),
    };
    let tiles = Tiles {
        cells: &vol.cells,
        tw,
        th,
        count: 1,
        gap: 0,
        labels: false,
    };
    let [lx, ly, lz] = lo;
    render_tiles(w, h, &tiles, bg, move |_, u, v| match k {
        0 => idx(lx + u, ly + v, z0),
        1 => idx(x0, ly + v, lz + u),
        _ => idx(lx + u, y0, lz + v),
    })
}

/// The feature-edge pieces mapped from retina coordinates through the stages into the 3D
/// volume's cell coordinates, with the parts inside the cutaway removed.
fn edges_3d(
    edges: &[RetinaEdge],
    shape: &[usize],
    n: [usize; 3],
    opts: &CompositeOptions,
) -> Vec<Edge3> {
    let ortho = opts.projection == Projection::Orthographic;
    let to_3d = |xi: &[f64]| -> DVec3 {
        let mut p = xi[..shape.len()].to_vec();
        let mut sh = shape.to_vec();
        let mut stage = 0;
        while sh.len() > 3 {
            let (f, d) = stage_params(&sh, opts.stages.get(stage).copied());
            p = stage_point(&sh, f, d, ortho, &p);
            sh.remove(0);
            stage += 1;
        }
        // numpy order (slice, row, column) → cell coordinates (column, row, slice).
        DVec3::new(p[2], p[1], p[0])
    };
    let mut out = Vec::with_capacity(edges.len());
    for e in edges {
        let (a, b) = (to_3d(&e.a), to_3d(&e.b));
        let piece = |t0: f64, t1: f64| Edge3 {
            a: a + (b - a) * t0,
            b: a + (b - a) * t1,
            depth: [
                e.depth[0] + (e.depth[1] - e.depth[0]) * t0,
                e.depth[0] + (e.depth[1] - e.depth[0]) * t1,
            ],
            visible: e.visible,
            color: e.color,
        };
        match opts
            .cutaway
            .as_ref()
            .and_then(|c: &Cutaway| c.inside(world_of(n, a), world_of(n, b)))
        {
            None => out.push(piece(0.0, 1.0)),
            Some((t0, t1)) => {
                if t0 > 0.0 {
                    out.push(piece(0.0, t0));
                }
                if t1 < 1.0 {
                    out.push(piece(t1, 1.0));
                }
            }
        }
    }
    out
}

/// The pieces projected to the picture, clipped to the part in front of a perspective eye.
fn project(edges: &[Edge3], cam: &Camera3) -> Vec<PixelEdge> {
    let near = cam.near();
    edges
        .iter()
        .filter_map(|e| {
            let (mut a, mut b) = (e.a, e.b);
            let [mut da, mut db] = e.depth;
            let (za, zb) = (cam.view_distance(a), cam.view_distance(b));
            if za < near && zb < near {
                return None;
            }
            if za < near || zb < near {
                let t = (near - za) / (zb - za);
                let q = a + (b - a) * t;
                let dq = da + (db - da) * t;
                if za < near {
                    (a, da) = (q, dq);
                } else {
                    (b, db) = (q, dq);
                }
            }
            let (pa, za) = cam.project(a)?;
            let (pb, zb) = cam.project(b)?;
            Some(PixelEdge {
                p: [pa, pb],
                z: [za, zb],
                depth: [da, db],
                visible: e.visible,
                color: e.color,
            })
        })
        .collect()
}
