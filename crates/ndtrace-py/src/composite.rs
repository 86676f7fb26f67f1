//! `_ndtrace.composite`: a retina (C-contiguous float32 rgba `(..., 4)` and optional depth) and
//! a dict of options in, a float32 picture `(H, W, 4)` out. The dict is deserialized into the
//! core's `CompositeOptions` — the same struct as a scene's `[composite]` table — so its keys,
//! defaults and range checks are the core's; the Python wrapper `ndtrace.composite` documents
//! them.

use crate::errors::{guarded, to_py_err};
use crate::scene::CompiledScene;
use ndtrace::camera::Projection;
use ndtrace::composite::SceneProbe;
use ndtrace::composite::{
    self as core, CompositeMode, CompositeOptions, EdgeColorBy, RetinaCamera, RetinaEdge,
    RetinaExtras, MAX_RETINA_DIM,
};
use ndtrace::render::probe::ScenePicture;
use ndtrace::scene::desc::ColorBy;
use ndtrace::scene::{self, PathError};
use ndtrace::texture::{colormap, palette};
use ndtrace::{names, with_scene, NdError};
use numpy::{PyArray1, PyArray4, PyArrayMethods, PyReadonlyArrayDyn, PyUntypedArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList, PyTuple};

type Arr<'py> = PyReadonlyArrayDyn<'py, f32>;

/// The options a dict gives (keys missing from it keep their defaults).
fn options_from(dict: &Bound<'_, PyAny>) -> Result<CompositeOptions, PathError> {
    scene::deserialize(&mut pythonize::Depythonizer::from_object(dict))
}

/// A retina and its extras, checked and borrowed from the numpy arrays.
struct Input<'a> {
    shape: Vec<usize>,
    rgba: &'a [f32],
    depth: Option<&'a [f32]>,
    normal: Option<&'a [f32]>,
    camera: Option<RetinaCamera>,
    edges: Vec<RetinaEdge>,
    object: Option<&'a [i32]>,
    legend_rows: usize,
}

impl Input<'_> {
    fn extras(&self) -> RetinaExtras<'_> {
        RetinaExtras {
            normal: self.normal,
            camera: self.camera.clone(),
            edges: &self.edges,
            object: self.object,
            scene: None,
            legend_rows: self.legend_rows,
        }
    }
}

/// Runs `f` with `extras` and, when `scene` is given, the scene as pictures ask it (N = 4).
fn with_probe<T>(
    scene: Option<&CompiledScene>,
    extras: &RetinaExtras<'_>,
    f: impl FnOnce(&RetinaExtras<'_>) -> T,
) -> T {
    match scene {
        None => f(extras),
        Some(cs) => with_scene!(cs.any(), s, _N => {
            let picture = ScenePicture::new(s);
            let probed = RetinaExtras {
                scene: picture.as_ref().map(|p| p as &dyn SceneProbe),
                ..extras.clone()
            };
            f(&probed)
        }),
    }
}

/// The camera of a dict with `orientation` (N×N row-major floats), `cell` and `perspective`.
fn camera_of(c: &Bound<'_, PyAny>) -> PyResult<RetinaCamera> {
    Ok(RetinaCamera {
        orientation: c.get_item("orientation")?.extract()?,
        cell: c.get_item("cell")?.extract()?,
        perspective: c.get_item("perspective")?.extract()?,
    })
}

/// The options of the dict (None: every default), errors naming the key.
fn options_arg(options: Option<&Bound<'_, PyAny>>) -> PyResult<CompositeOptions> {
    match options {
        None => Ok(CompositeOptions::default()),
        Some(dict) => options_from(dict).map_err(|e| {
            let arg = if e.path.is_empty() {
                "options".to_string()
            } else {
                e.path
            };
            to_py_err(NdError::Value {
                arg,
                message: e.message,
            })
        }),
    }
}

fn input<'a>(
    rgba: &'a Arr<'_>,
    depth: &'a Option<Arr<'_>>,
    normal: &'a Option<Arr<'_>>,
    camera: Option<&Bound<'_, PyAny>>,
    edges: &Option<PyReadonlyArrayDyn<'_, f64>>,
    object: &'a Option<PyReadonlyArrayDyn<'_, i32>>,
) -> PyResult<Input<'a>> {
    let dims = rgba.shape().to_vec();
    if dims.len() < 2 || dims[dims.len() - 1] != 4 {
        return Err(PyValueError::new_err(format!(
            "retina: expected an rgba array of shape (..., 4), got {dims:?}"
        )));
    }
    let shape = dims[..dims.len() - 1].to_vec();
    let rgba = rgba
        .as_slice()
        .map_err(|_| PyValueError::new_err("retina: expected a C-contiguous float32 rgba array"))?;
    let depth = match depth {
        Some(d) => {
            if d.shape() != shape.as_slice() {
                return Err(PyValueError::new_err(format!(
                    "depth: expected shape {shape:?} (the rgba array's without its last axis), got {:?}",
                    d.shape()
                )));
            }
            Some(d.as_slice().map_err(|_| {
                PyValueError::new_err("depth: expected a C-contiguous float32 array")
            })?)
        }
        None => None,
    };
    let m = shape.len();
    let normal = match normal {
        Some(nrm) => {
            let mut want = shape.clone();
            want.push(m + 1);
            if nrm.shape() != want.as_slice() {
                return Err(PyValueError::new_err(format!(
                    "normal: expected shape {want:?} (the retina's cells × N), got {:?}",
                    nrm.shape()
                )));
            }
            Some(nrm.as_slice().map_err(|_| {
                PyValueError::new_err("normal: expected a C-contiguous float32 array")
            })?)
        }
        None => None,
    };
    let camera = camera.map(camera_of).transpose()?;
    let edges: Vec<RetinaEdge> = match edges {
        None => Vec::new(),
        Some(e) => {
            let width = 2 * m + 6;
            let flat = e.as_slice().map_err(|_| {
                PyValueError::new_err("edges: expected a C-contiguous float64 array")
            })?;
            if m > MAX_RETINA_DIM || flat.len() % width != 0 {
                return Err(PyValueError::new_err(format!(
                    "edges: expected rows of {width} floats (two ends of {m} coordinates, two depths, visible, RGB)"
                )));
            }
            flat.chunks_exact(width)
                .map(|r| {
                    let mut e = RetinaEdge {
                        a: [0.0; MAX_RETINA_DIM],
                        b: [0.0; MAX_RETINA_DIM],
                        depth: [r[2 * m], r[2 * m + 1]],
                        visible: r[2 * m + 2] != 0.0,
                        color: [r[2 * m + 3], r[2 * m + 4], r[2 * m + 5]].map(|c| c as f32),
                    };
                    e.a[..m].copy_from_slice(&r[..m]);
                    e.b[..m].copy_from_slice(&r[m..2 * m]);
                    e
                })
                .collect()
        }
    };
    let object = match object {
        Some(o) => {
            if o.shape() != shape.as_slice() {
                return Err(PyValueError::new_err(format!(
                    "object_id: expected shape {shape:?} (the retina's cells), got {:?}",
                    o.shape()
                )));
            }
            Some(o.as_slice().map_err(|_| {
                PyValueError::new_err("object_id: expected a C-contiguous int32 array")
            })?)
        }
        None => None,
    };
    Ok(Input {
        shape,
        rgba,
        depth,
        normal,
        camera,
        edges,
        object,
        legend_rows: 0,
    })
}

/// Composites a retina into a picture `(H, W, 4)` with the options of the dict `options` (None:
/// every default), or with `turntable = F > 0` into its F frames `(F, H, W, 4)`;
/// `threads=None` uses every core (the picture is the same whatever the number).
///
/// `normal` (the retina's `(..., N)` float32 normals), `camera` (a dict with `orientation`,
/// N×N row-major floats, `cell` and `perspective`) and `edges` (float64 rows
/// `[a (N−1), b (N−1), depth_a, depth_b, visible, r, g, b]`) are what the illustrative mode
/// uses; `scene` (the `CompiledScene` the retina was traced from) and `object_id` (its int32
/// objects) what a picture drawn at its own resolution uses (`detail = "scene"`, N = 4);
/// `legend_rows` rows of legend are left free at the bottom (see `picture_layout`).
#[pyfunction]
#[pyo3(signature = (rgba, depth=None, options=None, threads=None, normal=None, camera=None, edges=None, scene=None, object_id=None, legend_rows=0))]
#[allow(clippy::too_many_arguments)]
fn composite<'py>(
    py: Python<'py>,
    rgba: Arr<'py>,
    depth: Option<Arr<'py>>,
    options: Option<&Bound<'py, PyAny>>,
    threads: Option<usize>,
    normal: Option<Arr<'py>>,
    camera: Option<&Bound<'py, PyAny>>,
    edges: Option<PyReadonlyArrayDyn<'py, f64>>,
    scene: Option<Bound<'py, CompiledScene>>,
    object_id: Option<PyReadonlyArrayDyn<'py, i32>>,
    legend_rows: usize,
) -> PyResult<Bound<'py, PyAny>> {
    let opts = options_arg(options)?;
    let mut inp = input(&rgba, &depth, &normal, camera, &edges, &object_id)?;
    inp.legend_rows = legend_rows;
    let extras = inp.extras();
    let pool = crate::thread_pool(threads)?;
    let frames = opts.turntable;
    let compiled = scene.as_ref().map(|b| b.get());
    if frames == 0 {
        let run = || {
            with_probe(compiled, &extras, |extras| {
                core::composite_retina(inp.rgba, inp.depth, &inp.shape, extras, &opts)
            })
        };
        let image = py.detach(|| {
            guarded("composite", || match &pool {
                Some(p) => p.install(run),
                None => run(),
            })
        })?;
        let (h, w) = (image.height, image.width);
        return Ok(PyArray1::from_vec(py, image.rgba)
            .reshape([h, w, 4])?
            .into_any());
    }
    // A turntable: the frames copied one by one into the array returned, so that they are
    // held once (its size checked by the memory guard before it is allocated).
    opts.validate_for(&inp.shape, inp.depth.is_some())
        .map_err(|e| to_py_err(e.into()))?;
    core::check_memory(&inp.shape, &opts, frames).map_err(to_py_err)?;
    let (w, h) = opts.size;
    let frame_len = h * w * 4;
    let array = PyArray4::<f32>::zeros(py, [frames, h, w, 4], false);
    {
        let mut out = array.readwrite();
        let flat = out
            .as_slice_mut()
            .map_err(|e| PyValueError::new_err(e.to_string()))?;
        let mut run = || {
            with_probe(compiled, &extras, |extras| {
                core::composite_turntable_each(
                    inp.rgba,
                    inp.depth,
                    &inp.shape,
                    extras,
                    &opts,
                    frames,
                    |k, image| {
                        flat[k * frame_len..(k + 1) * frame_len].copy_from_slice(&image.rgba)
                    },
                )
            })
        };
        py.detach(|| {
            guarded("composite", || match &pool {
                Some(p) => p.install(run),
                None => run(),
            })
        })?;
    }
    Ok(array.into_any())
}

/// Checks with the core's memory guard that compositing a retina of numpy `shape` (without
/// the channel axis) with the options of the dict fits, before anything is traced: the
/// refusal names `size` (or `turntable`) and the limit.
#[pyfunction]
fn check_picture_memory(shape: Vec<usize>, options: Option<&Bound<'_, PyAny>>) -> PyResult<()> {
    let opts = options_arg(options)?;
    core::check_memory(&shape, &opts, opts.turntable).map_err(to_py_err)
}

/// Refuses, as a ValueError naming `what` and the limit, a request for `bytes` (an estimate)
/// that the core's memory guard would refuse: what the Python side checks before it allocates
/// arrays whose size comes from its input.
#[pyfunction]
fn check_memory(bytes: f64, what: &str) -> PyResult<()> {
    ndtrace::memory::check(bytes, what).map_err(PyValueError::new_err)
}

/// The feature-edge pieces the illustrative picture of `options` draws (one view), as float64
/// rows `[x0, y0, x1, y1, depth0, depth1, r, g, b, visible, width, opacity]`: ends in picture
/// pixels (x right, y down), their N-D depths, the piece's linear RGB, its width (times the
/// edge width) and its strength as the picture draws them at its middle's depth.
#[pyfunction]
#[pyo3(signature = (rgba, depth=None, options=None, threads=None, normal=None, camera=None, edges=None, scene=None, object_id=None, legend_rows=0))]
#[allow(clippy::too_many_arguments)]
fn picture_edges<'py>(
    py: Python<'py>,
    rgba: Arr<'py>,
    depth: Option<Arr<'py>>,
    options: Option<&Bound<'py, PyAny>>,
    threads: Option<usize>,
    normal: Option<Arr<'py>>,
    camera: Option<&Bound<'py, PyAny>>,
    edges: Option<PyReadonlyArrayDyn<'py, f64>>,
    scene: Option<Bound<'py, CompiledScene>>,
    object_id: Option<PyReadonlyArrayDyn<'py, i32>>,
    legend_rows: usize,
) -> PyResult<Bound<'py, PyAny>> {
    let opts = options_arg(options)?;
    let mut inp = input(&rgba, &depth, &normal, camera, &edges, &object_id)?;
    inp.legend_rows = legend_rows;
    let extras = inp.extras();
    let pool = crate::thread_pool(threads)?;
    let compiled = scene.as_ref().map(|b| b.get());
    let run = || {
        with_probe(compiled, &extras, |extras| {
            core::picture_edges(inp.rgba, inp.depth, &inp.shape, extras, &opts)
        })
    };
    let pieces = py.detach(|| {
        guarded("picture_edges", || match &pool {
            Some(p) => p.install(run),
            None => run(),
        })
    })?;
    let count = pieces.len();
    let colors = core::overlay::EdgeColors::new(&pieces, &opts);
    let flat: Vec<f64> = pieces
        .iter()
        .flat_map(|e| {
            let mid = 0.5 * (e.depth[0] + e.depth[1]);
            let c = colors.at(e, mid);
            let (width, strength) = colors.weight(mid);
            [
                e.p[0][0],
                e.p[0][1],
                e.p[1][0],
                e.p[1][1],
                e.depth[0],
                e.depth[1],
                f64::from(c[0]),
                f64::from(c[1]),
                f64::from(c[2]),
                f64::from(u8::from(e.visible)),
                width,
                f64::from(strength),
            ]
        })
        .collect();
    Ok(PyArray1::from_vec(py, flat)
        .reshape([count, 12])?
        .into_any())
}

/// Every composite option with its default, as a dict in the order of the fields.
#[pyfunction]
fn composite_defaults(py: Python<'_>) -> PyResult<Bound<'_, PyAny>> {
    pythonize::pythonize(py, &CompositeOptions::default().with_every_key())
        .map_err(|e| PyValueError::new_err(e.to_string()))
}

/// Checks the composite options of a dict on their own, without a retina (what a scene's
/// `[composite]` table is checked for); errors read `name: composite.key: message`.
#[pyfunction]
fn check_composite(options: &Bound<'_, PyAny>, name: &str) -> PyResult<()> {
    let located = |path: &str, message: String| {
        to_py_err(NdError::Scene {
            location: name.to_string(),
            path: if path.is_empty() {
                "composite".to_string()
            } else {
                format!("composite.{path}")
            },
            message,
        })
    };
    let opts = options_from(options).map_err(|e| located(&e.path, e.message))?;
    opts.validate().map_err(|e| located(&e.key, e.message))
}

/// A rectangle as a dict `{x, y, w, h}`.
fn rect<'py>(py: Python<'py>, r: &core::Rect) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("x", r.x)?;
    d.set_item("y", r.y)?;
    d.set_item("w", r.w)?;
    d.set_item("h", r.h)?;
    Ok(d)
}

/// Where everything of the picture of `options` goes, for a retina of numpy `shape` with
/// `legend_rows` rows of legend: a dict with `size` (W, H), `text` (the text size, pixels),
/// `caption`, `legend` and `axes` (rectangles `{x, y, w, h}` or None) and `panels` (each
/// `{rect, title, title_band}`). `camera` (as for `composite`, with the camera's `position`)
/// gives the sections' titles in the scene's units where it can.
#[pyfunction]
#[pyo3(signature = (shape, options=None, legend_rows=0, camera=None))]
fn picture_layout<'py>(
    py: Python<'py>,
    shape: Vec<usize>,
    options: Option<&Bound<'py, PyAny>>,
    legend_rows: usize,
    camera: Option<&Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let opts = options_arg(options)?;
    if !(1..=7).contains(&shape.len()) || shape.contains(&0) {
        return Err(PyValueError::new_err(format!(
            "shape: a retina has 1 to 7 axes of at least one cell, got {shape:?}"
        )));
    }
    let cam = camera.map(camera_of).transpose()?;
    let position: Option<Vec<f64>> = match camera {
        Some(c) => c
            .get_item("position")
            .ok()
            .map(|p| p.extract())
            .transpose()?,
        None => None,
    };
    let located = match (&cam, &position) {
        (Some(c), Some(p)) => Some((c, p.as_slice())),
        _ => None,
    };
    let l = core::picture_layout(&opts, &shape, legend_rows, located);
    let d = PyDict::new(py);
    d.set_item("size", l.size)?;
    d.set_item("text", l.text)?;
    let opt_rect = |r: &Option<core::Rect>| -> PyResult<Bound<'py, PyAny>> {
        match r {
            Some(r) => Ok(rect(py, r)?.into_any()),
            None => Ok(py.None().into_bound(py)),
        }
    };
    d.set_item("caption", opt_rect(&l.caption)?)?;
    d.set_item("legend", opt_rect(&l.legend)?)?;
    d.set_item("axes", opt_rect(&l.axes)?)?;
    let panels = PyList::empty(py);
    for p in &l.panels {
        let e = PyDict::new(py);
        e.set_item("rect", rect(py, &p.rect)?)?;
        e.set_item("title", p.title.clone())?;
        e.set_item("title_band", opt_rect(&p.title_band)?)?;
        panels.append(e)?;
    }
    d.set_item("panels", panels)?;
    Ok(d)
}

/// The N-D axes glyph's arrows (see the core's `composite::axis_arrows`) for a retina of
/// numpy `shape`, its `camera` (as for `composite`) and the options: a list of dicts with
/// the axis' `label`, its `tip` (x right, y down, at most 1 long) and `toward` (−1 … 1, how
/// far it points toward the N-D eye). `frame` (N rows of N numbers, default the identity)
/// has the axes shown as its columns; without it the options' `axes_frame`.
#[pyfunction]
#[pyo3(signature = (shape, camera, options=None, frame=None))]
fn axis_arrows<'py>(
    py: Python<'py>,
    shape: Vec<usize>,
    camera: &Bound<'py, PyAny>,
    options: Option<&Bound<'py, PyAny>>,
    frame: Option<Vec<Vec<f64>>>,
) -> PyResult<Bound<'py, PyList>> {
    let opts = options_arg(options)?;
    let cam = camera_of(camera)?;
    let frame = frame.or_else(|| opts.axes_frame.clone());
    let list = PyList::empty(py);
    for a in core::axis_arrows(&cam, frame.as_deref(), &shape, &opts) {
        let e = PyDict::new(py);
        e.set_item("label", a.label)?;
        e.set_item("tip", a.tip.to_vec())?;
        e.set_item("toward", a.toward)?;
        list.append(e)?;
    }
    Ok(list)
}

/// The 256 linear-RGB entries of the colormap `name` (`_r` reversed), as the tracer maps values.
#[pyfunction]
fn colormap_table(name: &str) -> PyResult<Vec<[f64; 3]>> {
    colormap::get(name).map(|m| m.table).ok_or_else(|| {
        PyValueError::new_err(format!(
            "unknown colormap \"{name}\" (known: {}; \"_r\" reverses one)",
            colormap::names().join(", ")
        ))
    })
}

/// The linear-RGB colours of the qualitative palette `name`.
#[pyfunction]
fn palette_colors(name: &str) -> PyResult<Vec<[f64; 3]>> {
    palette::get(name).map(|p| p.colors).ok_or_else(|| {
        PyValueError::new_err(format!(
            "unknown palette \"{name}\" (known: {})",
            palette::names().join(", ")
        ))
    })
}

/// Adds `composite`, `composite_defaults`, `check_composite`, the memory checks
/// (`check_picture_memory`, `check_memory`), `picture_layout`, `axis_arrows`, the colour tables and the names of the composite modes, projections, edge colourings,
/// `color_by` values, colormaps and palettes (`COMPOSITE_MODES`, `PROJECTIONS`,
/// `EDGE_COLOR_BY`, `COLOR_BY`, `COLORMAPS`, `PALETTES`).
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add_function(wrap_pyfunction!(composite, m)?)?;
    m.add_function(wrap_pyfunction!(picture_edges, m)?)?;
    m.add_function(wrap_pyfunction!(composite_defaults, m)?)?;
    m.add_function(wrap_pyfunction!(check_composite, m)?)?;
    m.add_function(wrap_pyfunction!(check_picture_memory, m)?)?;
    m.add_function(wrap_pyfunction!(check_memory, m)?)?;
    m.add_function(wrap_pyfunction!(picture_layout, m)?)?;
    m.add_function(wrap_pyfunction!(axis_arrows, m)?)?;
    m.add_function(wrap_pyfunction!(colormap_table, m)?)?;
    m.add_function(wrap_pyfunction!(palette_colors, m)?)?;
    m.add(
        "EDGE_COLOR_BY",
        PyTuple::new(py, names::variants::<EdgeColorBy>())?,
    )?;
    m.add("COLOR_BY", PyTuple::new(py, names::variants::<ColorBy>())?)?;
    m.add("COLORMAPS", PyTuple::new(py, colormap::names())?)?;
    m.add("PALETTES", PyTuple::new(py, palette::names())?)?;
    m.add(
        "COMPOSITE_MODES",
        PyTuple::new(py, names::variants::<CompositeMode>())?,
    )?;
    m.add(
        "PROJECTIONS",
        PyTuple::new(py, names::variants::<Projection>())?,
    )?;
    Ok(())
}
