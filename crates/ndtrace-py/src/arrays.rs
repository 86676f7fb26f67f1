//! numpy arrays inside scene dicts, passed to the core's description as flat buffers instead of
//! nested lists (which cost a Python float and a serde value per number): taken out of the dict
//! before it is deserialized, and put back as numpy arrays by `to_dict`.
//!
//! The keys of an object that may hold an array, and its form, are [`KEYS`]: an elevation
//! map's `field`, a mesh's or surface's `vertices`, `simplices`, `triangles` and `values`.

use ndtrace::scene::desc::{Column, FieldDesc, Grid, ObjectDesc, Rows, Shared, Table};
use ndtrace::scene::table::Number;
use ndtrace::scene::SceneDesc;
use ndtrace::NdError;
use numpy::ndarray::ArrayViewD;
use numpy::{
    Element, PyArray1, PyArrayDescrMethods, PyArrayMethods, PyReadonlyArrayDyn, PyUntypedArray,
    PyUntypedArrayMethods,
};
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict, PyList};

/// An object key that may hold a numpy array: its dimensions and element type.
struct Key {
    name: &'static str,
    ndim: usize,
    float: bool,
    /// What the array's axes index, for errors.
    axes: &'static str,
}

/// The array keys of an object.
static KEYS: [Key; 5] = [
    Key {
        name: "field",
        ndim: 3,
        float: true,
        axes: "[x, y, z]",
    },
    Key {
        name: "vertices",
        ndim: 2,
        float: true,
        axes: "(vertex, coordinate)",
    },
    Key {
        name: "simplices",
        ndim: 2,
        float: false,
        axes: "(simplex, vertex)",
    },
    Key {
        name: "triangles",
        ndim: 2,
        float: false,
        axes: "(triangle, vertex)",
    },
    Key {
        name: "values",
        ndim: 1,
        float: true,
        axes: "(vertex,)",
    },
];

/// An array's numbers, lent to the description or copied once into it, by key.
enum Payload {
    Field(Grid),
    Vertices(Table<f64>),
    Simplices(Table<i64>),
    Triangles(Table<i64>),
    Values(Shared<f64>),
}

/// An array taken out of `objects[index]`.
pub(crate) struct Taken {
    index: usize,
    payload: Payload,
}

/// `data` without its numpy arrays at the [`KEYS`] of its objects (shallow copies where one
/// was taken; the caller's dicts are not changed), and the arrays taken. An array must have
/// the key's dimensions and be float64 (or int64 for indices; the Python wrapper converts
/// other numeric dtypes); errors name `name` and the array's path.
pub(crate) fn take_arrays<'py>(
    data: &Bound<'py, PyAny>,
    name: &str,
) -> PyResult<(Bound<'py, PyAny>, Vec<Taken>)> {
    let py = data.py();
    let Ok(top) = data.cast::<PyDict>() else {
        return Ok((data.clone(), Vec::new()));
    };
    let Some(objects) = top.get_item("objects")? else {
        return Ok((data.clone(), Vec::new()));
    };
    let Ok(objects) = objects.cast::<PyList>() else {
        return Ok((data.clone(), Vec::new()));
    };
    let mut taken = Vec::new();
    let copies = PyList::empty(py);
    for (index, o) in objects.iter().enumerate() {
        let Ok(d) = o.cast::<PyDict>() else {
            copies.append(o)?;
            continue;
        };
        let mut copy: Option<Bound<'py, PyDict>> = None;
        for key in &KEYS {
            let Some(value) = d.get_item(key.name)? else {
                continue;
            };
            if value.cast::<PyUntypedArray>().is_err() {
                continue;
            }
            let payload = payload(&value, key).map_err(|message| {
                crate::errors::to_py_err(NdError::Scene {
                    location: name.to_string(),
                    path: format!("objects[{index}].{}", key.name),
                    message,
                })
            })?;
            let c = match copy.take() {
                Some(c) => c,
                None => d.copy()?,
            };
            c.set_item(key.name, py.None())?;
            copy = Some(c);
            taken.push(Taken { index, payload });
        }
        match copy {
            Some(c) => copies.append(c)?,
            None => copies.append(o)?,
        }
    }
    if taken.is_empty() {
        return Ok((data.clone(), taken));
    }
    let top = top.copy()?;
    top.set_item("objects", copies)?;
    Ok((top.into_any(), taken))
}

/// The numbers of an array at `key`, C order whatever its strides.
fn payload(value: &Bound<'_, PyAny>, key: &Key) -> Result<Payload, String> {
    let a = value.cast::<PyUntypedArray>().map_err(|e| e.to_string())?;
    let shape = a.shape().to_vec();
    if shape.len() != key.ndim {
        return Err(format!(
            "expected a {}-D array indexed {}, got shape {shape:?}",
            key.ndim, key.axes
        ));
    }
    if key.ndim == 2 && shape[1] == 0 && shape[0] > 0 {
        return Err(format!(
            "expected rows of numbers indexed {}, got shape {shape:?} (rows of none)",
            key.axes
        ));
    }
    let wrong_dtype = || {
        let want = if key.float { "a float64" } else { "an int64" };
        format!("expected {want} array, got dtype {}", a.dtype())
    };
    if key.float {
        let values = flat::<f64>(value).ok_or_else(wrong_dtype)?;
        Ok(match key.name {
            "field" => Payload::Field(
                Grid::new([shape[0], shape[1], shape[2]], values).ok_or_else(|| {
                    format!("an array of shape {shape:?} with a wrong number of values")
                })?,
            ),
            "vertices" => Payload::Vertices(table(shape[1], values)?),
            _ => Payload::Values(values),
        })
    } else {
        let t = table(shape[1], flat::<i64>(value).ok_or_else(wrong_dtype)?)?;
        Ok(match key.name {
            "simplices" => Payload::Simplices(t),
            _ => Payload::Triangles(t),
        })
    }
}

fn table<T: Number>(width: usize, values: Shared<T>) -> Result<Table<T>, String> {
    let rows = values.len().checked_div(width).unwrap_or(0);
    Table::new(width, values)
        .ok_or_else(|| format!("an array of {rows} rows of {width} with a wrong number of values"))
}

/// The numbers of an array of `T` in C order: lent without a copy when they lie in a `bytes`
/// object ([`owning_bytes`]), else copied once into a buffer of the description's own; `None`
/// for another dtype.
fn flat<T: Element + Number>(value: &Bound<'_, PyAny>) -> Option<Shared<T>> {
    let a = value.extract::<PyReadonlyArrayDyn<'_, T>>().ok()?;
    // `as_slice` also takes Fortran-ordered memory as it lies: only a C-ordered array's is
    // its C order.
    Some(match a.as_slice() {
        Ok(s) if a.is_c_contiguous() => {
            match owning_bytes(value, s.as_ptr().cast(), size_of_val(s)) {
                Some(bytes) if s.as_ptr().is_aligned() => Shared::lent(Lent {
                    _bytes: bytes.unbind(),
                    ptr: s.as_ptr(),
                    len: s.len(),
                }),
                _ => s.to_vec().into(),
            }
        }
        _ => {
            let view: ArrayViewD<'_, T> = a.as_array();
            view.iter().copied().collect::<Vec<T>>().into()
        }
    })
}

/// Numbers lent to the description by a `bytes` object, which is immutable: holding it keeps
/// them alive and unchanged, whatever becomes of the array that viewed them.
struct Lent<T> {
    _bytes: Py<PyBytes>,
    ptr: *const T,
    len: usize,
}

// SAFETY: the numbers lie in the held `bytes` object ([`owning_bytes`] checks it), which
// nothing writes to, so they may be read from any thread; the object is only dropped, which
// pyo3 defers to a thread that holds the GIL.
unsafe impl<T: Sync> Send for Lent<T> {}
unsafe impl<T: Sync> Sync for Lent<T> {}

impl<T> AsRef<[T]> for Lent<T> {
    fn as_ref(&self) -> &[T] {
        // SAFETY: `ptr` (aligned) and `len` are a slice of the held bytes' memory (see `flat`).
        unsafe { std::slice::from_raw_parts(self.ptr, self.len) }
    }
}

/// The `bytes` object that holds the `size` bytes at `data` (the memory of the numpy array
/// `value`), found along the array's `base` chain and checked to contain them; `None` when
/// there is none (or `size` is 0). Only such memory is lent: a `bytes` object cannot change,
/// while an array's own memory can (through an older view, `resize`, `__setstate__`, or after
/// `setflags(write=True)`). A `base` that lies cannot fool the check: the memory must lie
/// within the object found.
fn owning_bytes<'py>(
    value: &Bound<'py, PyAny>,
    data: *const u8,
    size: usize,
) -> Option<Bound<'py, PyBytes>> {
    let mut a = value.clone();
    // Views of views end in a few steps (numpy collapses chains of views); the bound stops a
    // `base` that loops.
    for _ in 0..64 {
        let base = a.getattr("base").ok()?;
        if let Ok(bytes) = base.cast_exact::<PyBytes>() {
            let held = bytes.as_bytes().as_ptr_range();
            let range = data..data.wrapping_add(size);
            return (size > 0 && held.start <= range.start && range.end <= held.end)
                .then(|| bytes.clone());
        }
        base.cast::<PyUntypedArray>().ok()?;
        a = base;
    }
    None
}

/// Whether the loader reads the numbers of `value`, a C-ordered, aligned numpy array, in place
/// instead of copying them: whether they lie in a `bytes` object (`np.frombuffer(b)` of bytes
/// `b`, or a view of one), which cannot change. The Python `Scene` keeps its snapshots of
/// arrays in `bytes` and asks this before it makes one (`_snapshot`).
#[pyfunction]
pub(crate) fn lendable(value: &Bound<'_, PyAny>) -> bool {
    let Ok(a) = value.cast::<PyUntypedArray>() else {
        return false;
    };
    if !a.is_c_contiguous() || !a.is_aligned() {
        return false;
    }
    let size = a.len() * a.dtype().itemsize();
    // SAFETY: reads the data pointer of a live array object.
    let data = unsafe { (*a.as_array_ptr()).data } as *const u8;
    owning_bytes(value, data, size).is_some()
}

/// Puts the arrays taken by [`take_arrays`] into the deserialized description.
pub(crate) fn put_arrays(desc: &mut SceneDesc, taken: Vec<Taken>) {
    for t in taken {
        let Some(o) = desc.objects.get_mut(t.index) else {
            continue;
        };
        match t.payload {
            Payload::Field(g) => o.field = Some(FieldDesc::Array(g)),
            Payload::Vertices(v) => o.vertices = Some(Rows::Array(v)),
            Payload::Simplices(s) => o.simplices = Some(Rows::Array(s)),
            Payload::Triangles(t) => o.triangles = Some(Rows::Array(t)),
            Payload::Values(v) => o.values = Some(Column::Array(v)),
        }
    }
}

/// The arrays of an object, by key, as numpy arrays (and the object without them).
fn object_arrays<'py>(
    py: Python<'py>,
    o: &mut ObjectDesc,
) -> PyResult<Vec<(&'static str, Bound<'py, PyAny>)>> {
    fn rows<'py, T: Element + ndtrace::scene::table::Number>(
        py: Python<'py>,
        t: &Table<T>,
    ) -> PyResult<Bound<'py, PyAny>> {
        Ok(PyArray1::from_slice(py, t.values())
            .reshape([t.rows(), t.width()])?
            .into_any())
    }
    let mut out = Vec::new();
    if let Some(FieldDesc::Array(g)) = &o.field {
        out.push((
            "field",
            PyArray1::from_slice(py, g.values())
                .reshape(g.shape())?
                .into_any(),
        ));
        o.field = None;
    }
    if let Some(Rows::Array(t)) = &o.vertices {
        out.push(("vertices", rows(py, t)?));
        o.vertices = None;
    }
    if let Some(Rows::Array(t)) = &o.simplices {
        out.push(("simplices", rows(py, t)?));
        o.simplices = None;
    }
    if let Some(Rows::Array(t)) = &o.triangles {
        out.push(("triangles", rows(py, t)?));
        o.triangles = None;
    }
    if let Some(Column::Array(v)) = &o.values {
        out.push(("values", PyArray1::from_slice(py, v).into_any()));
        o.values = None;
    }
    Ok(out)
}

/// `desc` as plain Python data with its arrays as numpy arrays (no nested lists).
pub(crate) fn to_dict<'py>(py: Python<'py>, desc: &SceneDesc) -> PyResult<Bound<'py, PyAny>> {
    // A clone shares the arrays' buffers; the arrays are taken out of it before pythonize.
    let mut lean = desc.clone();
    let mut arrays = Vec::new();
    for (i, o) in lean.objects.iter_mut().enumerate() {
        for (key, a) in object_arrays(py, o)? {
            arrays.push((i, key, a));
        }
    }
    let out = pythonize::pythonize(py, &lean)
        .map_err(|e| pyo3::exceptions::PyValueError::new_err(e.to_string()))?;
    if !arrays.is_empty() {
        let objects = out.get_item("objects")?;
        for (i, key, a) in arrays {
            objects.get_item(i)?.set_item(key, a)?;
        }
    }
    Ok(out)
}
