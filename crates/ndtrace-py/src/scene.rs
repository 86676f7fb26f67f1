//! Scenes and tracing: `_ndtrace.load_file`, `_ndtrace.load_dict`, and the `CompiledScene`
//! class (a validated description plus its built, traceable scene and BVH).

use crate::errors::{guarded, to_py_err};
use crate::mesh::PyMeshReader;
use ndtrace::render::pool;
use ndtrace::render::{self, Progress, Retina};
use ndtrace::scene::desc::RenderMode;
use ndtrace::scene::{self, AnyScene, MeshReader, SceneDesc};
use ndtrace::{with_scene, NdError};
use numpy::ndarray::{ArrayViewMutD, IxDyn};
use numpy::PyArrayDyn;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::PathBuf;
use std::sync::atomic::Ordering;
use std::time::Duration;

/// The colormap's name as the material gave it (with its `_r`), else the core's.
fn colormap_name(m: &ndtrace::scene::desc::MaterialDesc, base: &str) -> String {
    match &m.colormap {
        Some(name) => name.clone(),
        None if m.color_by == Some(ndtrace::scene::desc::ColorBy::Depth) => {
            ndtrace::scene::DEPTH_COLORMAP.to_string()
        }
        None => base.to_string(),
    }
}

/// A validated scene with its BVH, built once and reused by every trace.
#[pyclass(module = "ndtrace._ndtrace", frozen)]
pub struct CompiledScene {
    desc: SceneDesc,
    scene: AnyScene,
}

impl CompiledScene {
    /// The built scene.
    pub(crate) fn any(&self) -> &AnyScene {
        &self.scene
    }
}

#[pymethods]
impl CompiledScene {
    /// Dimension N.
    #[getter]
    fn dim(&self) -> usize {
        self.scene.dim()
    }

    /// Warnings from building (e.g. skipped degenerate simplices).
    #[getter]
    fn warnings(&self) -> Vec<String> {
        self.scene.warnings().to_vec()
    }

    /// Retina shape in numpy order.
    #[getter]
    fn retina_shape(&self) -> Vec<usize> {
        with_scene!(&self.scene, s, _N => s.camera.numpy_shape())
    }

    /// Camera orientation (rows) as built; for `look_at` cameras the matrix the course's
    /// convention produces.
    #[getter]
    fn camera_orientation(&self) -> Vec<Vec<f64>> {
        with_scene!(&self.scene, s, _N => s.camera.orientation.iter().map(|r| r.to_vec()).collect())
    }

    /// Number of simplices in the BVH and its memory in bytes.
    fn bvh_stats(&self) -> (usize, usize, usize) {
        with_scene!(&self.scene, s, _N => (s.instances.len(), s.instances.node_count(), s.instances.memory_bytes()))
    }

    /// The camera section of the description as TOML (stored in retina files).
    fn camera_toml(&self) -> PyResult<String> {
        // Only the camera section is wanted: serialize the description without its objects
        // (whose inline meshes would cost time in proportion to the scene's size).
        let d = &self.desc;
        let camera_only = scene::SceneDesc {
            dim: d.dim,
            background: d.background.clone(),
            ambient: d.ambient.clone(),
            camera: d.camera.clone(),
            lights: Vec::new(),
            objects: Vec::new(),
            render: d.render.clone(),
            composite: None,
            animation: None,
            slice: None,
            clip: Vec::new(),
            cap: false,
        };
        scene::to_toml(&camera_only)
            .map(|t| {
                let start = t.find("[camera]").unwrap_or(0);
                let rest = &t[start..];
                let end = rest[1..].find("\n[").map_or(rest.len(), |e| e + 2);
                rest[..end].trim_end().to_string()
            })
            .map_err(to_py_err)
    }

    /// Every object's feature edges (crease angle `angle`, degrees) split into the pieces the
    /// camera sees and those it does not: flat arrays for `ndtrace.edge_segments`.
    fn edge_segments<'py>(&self, py: Python<'py>, angle: f64) -> PyResult<Bound<'py, PyDict>> {
        let scene = &self.scene;
        with_scene!(scene, s, _N => {
            let segs = py.detach(|| guarded("edge_segments", || ndtrace::edges::edge_segments(s, angle)))?;
            crate::edges::segments_dict(py, &segs)
        })
    }

    /// The feature-edge pieces in retina coordinates (`ndtrace.composite`'s `edges`): float64
    /// rows `[a (N−1), b (N−1), depth_a, depth_b, visible, r, g, b]` (the colour of the
    /// edge's direction, linear RGB), flat.
    fn retina_edges<'py>(
        &self,
        py: Python<'py>,
        angle: f64,
    ) -> PyResult<Bound<'py, numpy::PyArray1<f64>>> {
        let scene = &self.scene;
        let rows = with_scene!(scene, s, _N => py
            .detach(|| guarded("retina_edges", || ndtrace::edges::retina_edges(s, angle)))?
            .into_iter()
            .flat_map(|e| {
                let m = _N - 1;
                let mut r = Vec::with_capacity(2 * m + 6);
                r.extend_from_slice(&e.a[..m]);
                r.extend_from_slice(&e.b[..m]);
                r.extend_from_slice(&e.depth);
                r.push(f64::from(u8::from(e.visible)));
                r.extend(e.color.map(f64::from));
                r
            })
            .collect::<Vec<f64>>());
        Ok(numpy::PyArray1::from_vec(py, rows))
    }

    /// The camera as the compositor needs it: a dict with `orientation` (N×N row-major),
    /// `position`, `cell` (side of a cell, at unit distance for perspective) and
    /// `perspective`.
    fn retina_camera<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        with_scene!(&self.scene, s, _N => {
            let c = &s.camera;
            let flat: Vec<f64> = c.orientation.iter().flatten().copied().collect();
            d.set_item("orientation", flat)?;
            d.set_item("position", c.position.to_vec())?;
            d.set_item("cell", c.cell)?;
            d.set_item(
                "perspective",
                c.projection == ndtrace::camera::Projection::Perspective,
            )?;
            d.set_item("position", c.position.to_vec())?;
        });
        Ok(d)
    }

    /// What the picture's legend says of each object: a list of dicts with its `label`, its
    /// `color` (linear RGB, after `color_by = "object"`), `color_by`, `palette`, `colormap`
    /// (`{"name", "range", "of": "values" | "depth"}`), `isolines` (`{"values", "color"}`)
    /// and, for `color_by = "cell"`, `cells` (per direction of cells: its `normal` in the
    /// object's own axes, the `count` of cells and their `color`) and `cell_class` (per
    /// simplex, the index of its direction in `cells`; `2³² − 1` for a degenerate one).
    fn legend_info<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, pyo3::types::PyList>> {
        let list = pyo3::types::PyList::empty(py);
        with_scene!(&self.scene, s, _N => {
            for (k, (o, d)) in s.objects.iter().zip(&self.desc.objects).enumerate() {
                let item = PyDict::new(py);
                item.set_item("index", k)?;
                item.set_item("label", d.label.clone())?;
                item.set_item("shape", pythonize::pythonize(py, &d.shape).map_err(|e| PyValueError::new_err(e.to_string()))?)?;
                item.set_item("color", o.material.color.to_vec())?;
                let color_by = o.material.color_by.map(|c| {
                    ndtrace::names::variants::<ndtrace::scene::desc::ColorBy>()[c as usize]
                });
                item.set_item("color_by", color_by)?;
                item.set_item("palette", o.material.palette.name)?;
                let t = o.texture.as_ref();
                let map = t.and_then(|t| {
                    t.depth.as_ref().map(|(m, r)| (m, r, "depth"))
                        .or(t.colormap.as_ref().map(|(m, r)| (m, r, "values")))
                });
                match map {
                    Some((m, r, of)) => {
                        let c = PyDict::new(py);
                        c.set_item("name", colormap_name(&d.material, m.name))?;
                        c.set_item("range", r.to_vec())?;
                        c.set_item("of", of)?;
                        item.set_item("colormap", c)?;
                    }
                    None => item.set_item("colormap", py.None())?,
                }
                match t.and_then(|t| t.isolines.as_ref()) {
                    Some(i) => {
                        let c = PyDict::new(py);
                        c.set_item("values", i.values.clone())?;
                        c.set_item("color", i.color.to_vec())?;
                        item.set_item("isolines", c)?;
                    }
                    None => item.set_item("isolines", py.None())?,
                }
                match t.and_then(|t| t.cells.as_ref()) {
                    Some(c) => {
                        let cells = pyo3::types::PyList::empty(py);
                        for ((n, count), color) in c.classes.normals.iter().zip(&c.classes.cells).zip(&c.colors) {
                            let e = PyDict::new(py);
                            e.set_item("normal", n.to_vec())?;
                            e.set_item("count", *count)?;
                            e.set_item("color", color.to_vec())?;
                            cells.append(e)?;
                        }
                        item.set_item("cells", cells)?;
                        item.set_item("cell_class", numpy::PyArray1::from_vec(py, c.classes.class.clone()))?;
                    }
                    None => {
                        item.set_item("cells", py.None())?;
                        item.set_item("cell_class", py.None())?;
                    }
                }
                list.append(item)?;
            }
        });
        Ok(list)
    }

    /// The directions of the feature edges (crease angle `angle`, degrees), for the legend of
    /// `edge_color_by = "direction"`: a list of dicts with the unit direction `own` in the
    /// object's own axes, the `object` and the `color` (linear RGB).
    fn edge_directions<'py>(
        &self,
        py: Python<'py>,
        angle: f64,
    ) -> PyResult<Bound<'py, pyo3::types::PyList>> {
        let list = pyo3::types::PyList::empty(py);
        with_scene!(&self.scene, s, _N => {
            let dirs = py.detach(|| guarded("edge_directions", || ndtrace::edges::edge_directions(s, angle)))?;
            for d in dirs {
                let e = PyDict::new(py);
                e.set_item("own", d.own.to_vec())?;
                e.set_item("object", d.object)?;
                e.set_item("color", d.color.to_vec())?;
                list.append(e)?;
            }
        });
        Ok(list)
    }

    /// The description as TOML.
    fn to_toml(&self) -> PyResult<String> {
        scene::to_toml(&self.desc).map_err(to_py_err)
    }

    /// The description as plain Python data (dicts, lists, numbers, strings; mesh and field
    /// arrays given as numpy arrays stay arrays unless `lists`).
    #[pyo3(signature = (lists = false))]
    fn to_dict<'py>(&self, py: Python<'py>, lists: bool) -> PyResult<Bound<'py, PyAny>> {
        if lists {
            return pythonize::pythonize(py, &self.desc)
                .map_err(|e| PyValueError::new_err(e.to_string()));
        }
        crate::arrays::to_dict(py, &self.desc)
    }

    /// The description of frame `k` of the scene's `[animation]` as plain Python data: the
    /// scene with that frame's rotation applied to the animation's target, without the table.
    fn animation_frame<'py>(&self, py: Python<'py>, k: u32) -> PyResult<Bound<'py, PyAny>> {
        let frame = guarded("animation_frame", || {
            scene::animation_frame(&self.desc, k, "<scene>")
        })?;
        crate::arrays::to_dict(py, &frame)
    }

    /// Frame `k` of the animation without a build (bit for bit the frame's description built
    /// anew): sharing this scene's objects and BVH when the camera moves, its BVHs (which hold
    /// the objects in their own space) when objects move; `None` when it cannot (build
    /// `animation_frame(k)` then).
    fn reused_frame(&self, k: u32) -> PyResult<Option<CompiledScene>> {
        let frame = guarded("reused_frame", || {
            scene::reused_frame(&self.desc, &self.scene, k, "<scene>").transpose()
        })?;
        Ok(frame.map(|(desc, scene)| CompiledScene { desc, scene }))
    }

    /// The (N−1)-dimensional slice of the scene by the hyperplane n̂·x = `offset`, built
    /// (`normal` None: the scene's `[slice]`).
    #[pyo3(signature = (normal=None, offset=0.0))]
    fn slice(
        &self,
        py: Python<'_>,
        normal: Option<Vec<f64>>,
        offset: f64,
    ) -> PyResult<CompiledScene> {
        let cut = normal.map(|normal| scene::desc::SliceDesc { normal, offset });
        py.detach(|| {
            guarded("slice_scene", || {
                let desc = scene::slice_scene(&self.desc, &self.scene, cut.as_ref(), "<slice>")?;
                let scene = scene::build_desc(&desc, "<slice>", None)?;
                Ok(CompiledScene { desc, scene })
            })
        })
    }

    /// Whether two scenes have equal descriptions.
    fn same_description(&self, other: &CompiledScene) -> bool {
        self.desc == other.desc
    }

    /// The retina cut into at most `count` slabs of whole chunks, as even as chunks allow:
    /// `(start, end)` cell ranges in memory order for `trace(cells=…)`.
    fn slabs(&self, count: usize) -> Vec<(usize, usize)> {
        with_scene!(&self.scene, s, _N => render::slabs(s, count))
            .into_iter()
            .map(|r| (r.start, r.end))
            .collect()
    }

    /// Traces the retina, or with `cells=(start, end)` (one of [`Self::slabs`]) only those
    /// cells, flat, with the bits the whole retina gives them. `threads=None` uses every core.
    /// `callback(done, total)` is called about ten times a second; Ctrl-C (or an exception in
    /// the callback) cancels within a fraction of a second. Returns a dict of numpy arrays.
    #[pyo3(signature = (threads=None, callback=None, cells=None))]
    fn trace<'py>(
        &self,
        py: Python<'py>,
        threads: Option<usize>,
        callback: Option<Bound<'py, PyAny>>,
        cells: Option<(usize, usize)>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let pool = crate::thread_pool(threads)?;
        let total = match cells {
            Some((a, b)) => b.saturating_sub(a),
            None => with_scene!(&self.scene, s, _N => s.camera.cell_count()),
        };
        let progress = Progress::default();
        let scene = &self.scene;
        let run = || match cells {
            Some((a, b)) => with_scene!(scene, s, _N => render::trace_slab(s, &progress, a..b)),
            None => with_scene!(scene, s, _N => render::trace(s, &progress)),
        };
        let mut interrupt: Option<PyErr> = None;
        let result = std::thread::scope(|sc| {
            let (done_tx, done_rx) = std::sync::mpsc::channel::<()>();
            let handle = sc.spawn(move || {
                let r = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| match &pool {
                    Some(p) => p.install(run),
                    None => run(),
                }));
                let _ = done_tx.send(());
                r
            });
            // Wake at once when the trace ends, else every 50 ms for Ctrl-C and progress.
            let done_rx = std::sync::Mutex::new(done_rx);
            let wait = || {
                done_rx
                    .lock()
                    .map_or(Ok(()), |rx| rx.recv_timeout(Duration::from_millis(50)))
            };
            while py.detach(wait) == Err(std::sync::mpsc::RecvTimeoutError::Timeout) {
                if interrupt.is_none() {
                    let polled = py.check_signals().and_then(|_| match &callback {
                        Some(cb) => cb
                            .call1((progress.done.load(Ordering::Relaxed), total))
                            .map(|_| ()),
                        None => Ok(()),
                    });
                    if let Err(e) = polled {
                        progress.cancel.store(true, Ordering::Relaxed);
                        interrupt = Some(e);
                    }
                }
            }
            handle.join()
        });
        if let Some(e) = interrupt {
            return Err(e);
        }
        // The thread catches the trace's panics itself (join's Err cannot happen then).
        let retina = match result {
            Ok(Ok(traced)) => traced.map_err(to_py_err)?,
            Ok(Err(payload)) | Err(payload) => {
                return Err(crate::errors::internal_error("trace", payload.as_ref()))
            }
        };
        if let Some(cb) = &callback {
            cb.call1((total, total))?;
        }
        retina_dict(py, retina)
    }
}

pub(crate) fn retina_dict(py: Python<'_>, r: Retina) -> PyResult<Bound<'_, PyDict>> {
    let d = PyDict::new(py);
    let shape = r.shape.clone();
    let with = |extra: usize| -> Vec<usize> {
        let mut s = shape.clone();
        if extra > 0 {
            s.push(extra);
        }
        s
    };
    d.set_item("dim", r.dim)?;
    d.set_item("rgba", handed(py, r.rgba, &with(4))?)?;
    d.set_item("depth", handed(py, r.depth, &with(0))?)?;
    d.set_item("normal", handed(py, r.normal, &with(r.dim))?)?;
    d.set_item("object_id", handed(py, r.object_id, &with(0))?)?;
    d.set_item("primitive_id", handed(py, r.primitive_id, &with(0))?)?;
    Ok(d)
}

/// A retina output buffer owned by the numpy array that views it (its base object); when numpy
/// frees the array, the buffer goes back to [`pool`] for the next trace to reuse.
#[pyclass(module = "ndtrace._ndtrace", frozen)]
struct RetinaBuffer {
    data: Buffer,
}

/// The buffer of a [`RetinaBuffer`], by element type.
enum Buffer {
    F32(Vec<f32>),
    I32(Vec<i32>),
    I64(Vec<i64>),
}

impl Drop for RetinaBuffer {
    fn drop(&mut self) {
        match std::mem::replace(&mut self.data, Buffer::F32(Vec::new())) {
            Buffer::F32(v) => pool::recycle(v),
            Buffer::I32(v) => pool::recycle(v),
            Buffer::I64(v) => pool::recycle(v),
        }
    }
}

/// A retina element type that a [`RetinaBuffer`] holds.
trait Handed: numpy::Element + pool::Pooled {
    fn wrap(v: Vec<Self>) -> Buffer;
}

macro_rules! handed {
    ($($t:ty => $variant:ident),*) => {$(
        impl Handed for $t {
            fn wrap(v: Vec<Self>) -> Buffer {
                Buffer::$variant(v)
            }
        }
    )*};
}
handed!(f32 => F32, i32 => I32, i64 => I64);

/// `v` as a C-contiguous numpy array of `shape` (no copy), owned by a [`RetinaBuffer`].
fn handed<'py, T: Handed>(
    py: Python<'py>,
    mut v: Vec<T>,
    shape: &[usize],
) -> PyResult<Bound<'py, PyArrayDyn<T>>> {
    if shape.iter().product::<usize>() != v.len() {
        return Err(PyValueError::new_err(format!(
            "retina buffer of {} elements does not have shape {shape:?}",
            v.len()
        )));
    }
    let ptr = v.as_mut_ptr();
    let owner = Bound::new(py, RetinaBuffer { data: T::wrap(v) })?;
    // SAFETY: `ptr` points to the `len` elements of the Vec now held by `owner`, which never
    // touches, moves or reallocates them until it is dropped; `owner` becomes the array's base
    // object, so it is dropped only after the array. The view is C-contiguous over exactly those
    // elements (the product of `shape` is the length).
    unsafe {
        let view = ArrayViewMutD::from_shape_ptr(IxDyn(shape), ptr);
        Ok(PyArrayDyn::borrow_from_array(&view, owner.into_any()))
    }
}

/// Frees the output buffers kept from dropped retinas for reuse by later traces
/// ([`pool`]); returns the bytes freed.
#[pyfunction]
fn release_buffers() -> usize {
    pool::release()
}

/// The reader of mesh files that are not `.npz`, as the core takes it.
fn as_reader(r: &Option<PyMeshReader>) -> Option<&dyn MeshReader> {
    r.as_ref().map(|r| r as &dyn MeshReader)
}

/// Loads and builds a TOML scene file; `reader(path, dim)` reads mesh files other than `.npz`.
#[pyfunction]
#[pyo3(signature = (path, reader=None))]
fn load_file(
    py: Python<'_>,
    path: PathBuf,
    reader: Option<Bound<'_, PyAny>>,
) -> PyResult<CompiledScene> {
    let reader = PyMeshReader::new(reader);
    let loaded = py.detach(|| {
        guarded("load_file", || {
            scene::load_file_with(&path, as_reader(&reader))
        })
    });
    let (desc, scene) = PyMeshReader::finish(&reader, loaded)?;
    Ok(CompiledScene { desc, scene })
}

/// Parses TOML text (named `name` in errors) and builds it; relative files resolve against `base`.
#[pyfunction]
#[pyo3(signature = (text, name="<string>", base=None, reader=None))]
fn load_toml(
    py: Python<'_>,
    text: &str,
    name: &str,
    base: Option<PathBuf>,
    reader: Option<Bound<'_, PyAny>>,
) -> PyResult<CompiledScene> {
    let reader = PyMeshReader::new(reader);
    let loaded = py.detach(|| {
        guarded("load_toml", || {
            scene::load_toml_with(text, name, base.as_deref(), as_reader(&reader))
        })
    });
    let (desc, scene) = PyMeshReader::finish(&reader, loaded)?;
    Ok(CompiledScene { desc, scene })
}

/// Builds a scene from plain Python data (dicts, lists, numbers, strings); errors are named
/// `name`; relative files resolve against `base`. With `like`, a description that differs from
/// `like`'s at most in its `[animation]` table shares `like`'s build (`scene::reanimated`).
#[pyfunction]
#[pyo3(signature = (data, name="<dict>", base=None, reader=None, like=None))]
fn load_dict(
    py: Python<'_>,
    data: &Bound<'_, PyAny>,
    name: &str,
    base: Option<PathBuf>,
    reader: Option<Bound<'_, PyAny>>,
    like: Option<PyRef<'_, CompiledScene>>,
) -> PyResult<CompiledScene> {
    let reader = PyMeshReader::new(reader);
    let (data, arrays) = crate::arrays::take_arrays(data, name)?;
    let mut de = pythonize::Depythonizer::from_object(&data);
    let mut desc = scene::deserialize(&mut de).map_err(|e| {
        to_py_err(NdError::Scene {
            location: name.to_string(),
            path: e.path,
            message: e.message,
        })
    })?;
    crate::arrays::put_arrays(&mut desc, arrays);
    if let Some(like) = like {
        if let Some(shared) = scene::reanimated(&desc, &like.desc, &like.scene, name) {
            let scene = shared.map_err(to_py_err)?;
            return Ok(CompiledScene { desc, scene });
        }
    }
    let built = py.detach(|| {
        guarded("load_dict", || {
            scene::build_desc_with(&desc, name, base.as_deref(), as_reader(&reader))
        })
    });
    let scene = PyMeshReader::finish(&reader, built)?;
    Ok(CompiledScene { desc, scene })
}

/// Adds the scene functions and class, and the names of the render modes (`RENDER_MODES`).
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<CompiledScene>()?;
    m.add(
        "RENDER_MODES",
        pyo3::types::PyTuple::new(m.py(), ndtrace::names::variants::<RenderMode>())?,
    )?;
    m.add_function(wrap_pyfunction!(release_buffers, m)?)?;
    m.add_function(wrap_pyfunction!(crate::arrays::lendable, m)?)?;
    m.add_function(wrap_pyfunction!(load_file, m)?)?;
    m.add_function(wrap_pyfunction!(load_toml, m)?)?;
    m.add_function(wrap_pyfunction!(load_dict, m)?)?;
    Ok(())
}
