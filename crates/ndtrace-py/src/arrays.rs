//! numpy arrays inside scene dicts, passed to the core's description as flat buffers instead of
//! nested lists (which cost a Python float and a serde value per number): taken out of the dict
//! before it is deserialized, and put back as numpy arrays by `to_dict`.
//!
//! Today that is an elevation object's `field` (a 128³ field is 2 M numbers).

use ndtrace::scene::desc::{FieldDesc, Grid};
use ndtrace::scene::SceneDesc;
use ndtrace::NdError;
use numpy::{PyArray1, PyArrayMethods, PyReadonlyArray3, PyUntypedArray, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

/// An array field taken out of `objects[index]`.
pub(crate) struct Taken {
    index: usize,
    grid: Grid,
}

/// `data` without its numpy `objects[i].field` arrays (shallow copies where one was taken; the
/// caller's dicts are not changed), and the arrays taken. An array must be 3-D float64 (the
/// Python wrapper converts numeric dtypes); errors name `name` and the field's path.
pub(crate) fn take_fields<'py>(
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
        let field = match o.cast::<PyDict>() {
            Ok(d) => d
                .get_item("field")?
                .filter(|f| f.cast::<PyUntypedArray>().is_ok()),
            Err(_) => None,
        };
        let Some(field) = field else {
            copies.append(o)?;
            continue;
        };
        let grid = grid(&field).map_err(|message| {
            crate::errors::to_py_err(NdError::Scene {
                location: name.to_string(),
                path: format!("objects[{index}].field"),
                message,
            })
        })?;
        let copy = o.cast::<PyDict>()?.copy()?;
        copy.set_item("field", py.None())?;
        copies.append(copy)?;
        taken.push(Taken { index, grid });
    }
    if taken.is_empty() {
        return Ok((data.clone(), taken));
    }
    let top = top.copy()?;
    top.set_item("objects", copies)?;
    Ok((top.into_any(), taken))
}

/// A 3-D float64 array's values, copied once into the description (C order whatever the
/// array's strides).
fn grid(field: &Bound<'_, PyAny>) -> Result<Grid, String> {
    let a = field.cast::<PyUntypedArray>().map_err(|e| e.to_string())?;
    let shape = a.shape().to_vec();
    let Ok(f) = field.extract::<PyReadonlyArray3<'_, f64>>() else {
        return Err(if shape.len() == 3 {
            format!("expected a float64 array, got dtype {}", a.dtype())
        } else {
            format!("expected a 3-D array indexed [x, y, z], got shape {shape:?}")
        });
    };
    // `as_slice` also takes Fortran-ordered memory as it lies: only a C-ordered array's is
    // the field's C order.
    let values: std::sync::Arc<[f64]> = match f.as_slice() {
        Ok(s) if f.is_c_contiguous() => s.into(),
        _ => f.as_array().iter().copied().collect(),
    };
    Grid::new([shape[0], shape[1], shape[2]], values)
        .ok_or_else(|| format!("an array of shape {shape:?} with a wrong number of values"))
}

/// Puts the fields taken by [`take_fields`] into the deserialized description.
pub(crate) fn put_fields(desc: &mut SceneDesc, taken: Vec<Taken>) {
    for t in taken {
        if let Some(o) = desc.objects.get_mut(t.index) {
            o.field = Some(FieldDesc::Array(t.grid));
        }
    }
}

/// `desc` as plain Python data with array fields as numpy arrays (no nested lists).
pub(crate) fn to_dict<'py>(py: Python<'py>, desc: &SceneDesc) -> PyResult<Bound<'py, PyAny>> {
    let arrays: Vec<(usize, &Grid)> = (desc.objects.iter().enumerate())
        .filter_map(|(i, o)| match &o.field {
            Some(FieldDesc::Array(g)) => Some((i, g)),
            _ => None,
        })
        .collect();
    let plain = |d: &SceneDesc| {
        pythonize::pythonize(py, d)
            .map_err(|e| pyo3::exceptions::PyValueError::new_err(e.to_string()))
    };
    if arrays.is_empty() {
        return plain(desc);
    }
    let mut lean = desc.clone();
    for &(i, _) in &arrays {
        lean.objects[i].field = None;
    }
    let out = plain(&lean)?;
    let objects = out.get_item("objects")?;
    for (i, g) in arrays {
        let a = PyArray1::from_slice(py, g.values()).reshape(g.shape())?;
        objects.get_item(i)?.set_item("field", a)?;
    }
    Ok(out)
}
