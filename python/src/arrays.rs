//! NumPy arrays in and out: `(n, 3)` positions of float64 or float32 (any real array-like is
//! taken), `(m, k)` integer index arrays, and copies out as float64 `(n, 3)`, int64 `(m, k)` and
//! float64 `(n,)` arrays. A wrong shape, type or value is a `tissue.MeshError` (a `ValueError`)
//! naming the argument.

use glam::Vec3;
use numpy::ndarray::{Array1, Array2};
use numpy::{
    PyArray1, PyArray2, PyArrayDescrMethods, PyArrayMethods, PyUntypedArray, PyUntypedArrayMethods,
};
use pyo3::prelude::*;

use crate::errors::bad_array;

/// `obj` as a NumPy array (`numpy.asarray`), with its number of columns checked.
fn as_array<'py>(
    obj: &Bound<'py, PyAny>,
    field: &str,
    columns: &[usize],
    what: &str,
) -> PyResult<Bound<'py, PyUntypedArray>> {
    let py = obj.py();
    let np = numpy::get_array_module(py)?;
    let array = np
        .call_method1("asarray", (obj,))
        .map_err(|e| bad_array(py, field, format!("`{field}` is not an array: {e}")))?;
    let array = array.cast_into::<PyUntypedArray>().map_err(|_| {
        bad_array(
            py,
            field,
            format!("`{field}` must be a NumPy array of {what}"),
        )
    })?;
    let shape = array.shape();
    let wanted = columns
        .iter()
        .map(|c| format!("(n, {c})"))
        .collect::<Vec<_>>()
        .join(" or ");
    if shape.len() != 2 || !columns.contains(&shape[1]) {
        return Err(bad_array(
            py,
            field,
            format!("`{field}` must be an array of shape {wanted} ({what}), got shape {shape:?}"),
        ));
    }
    Ok(array)
}

/// An `(n, 3)` array of points (float64 or float32; integers are taken too), as `Vec3`s;
/// every coordinate must be finite.
pub fn points(obj: &Bound<'_, PyAny>, field: &str) -> PyResult<Vec<Vec3>> {
    let py = obj.py();
    let array = as_array(obj, field, &[3], "x, y, z per row")?;
    let kind = array.dtype().kind();
    let out: Vec<Vec3> = match kind {
        b'f' if array.dtype().itemsize() == 4 => {
            let a = array.cast::<PyArray2<f32>>()?.readonly();
            let view = a.as_array();
            view.rows()
                .into_iter()
                .map(|r| Vec3::new(r[0], r[1], r[2]))
                .collect()
        }
        b'f' | b'i' | b'u' => {
            let np = numpy::get_array_module(py)?;
            let converted = np.call_method1("ascontiguousarray", (&array, "float64"))?;
            let a = converted.cast_into::<PyArray2<f64>>()?.readonly();
            let view = a.as_array();
            view.rows()
                .into_iter()
                .map(|r| Vec3::new(r[0] as f32, r[1] as f32, r[2] as f32))
                .collect()
        }
        other => {
            return Err(bad_array(
                py,
                field,
                format!(
                    "`{field}` must hold real numbers (float64 or float32), got dtype kind '{}'",
                    other as char
                ),
            ))
        }
    };
    if let Some(row) = out.iter().position(|p| !p.is_finite()) {
        return Err(bad_array(
            py,
            field,
            format!("`{field}` row {row} is not finite (or too large for float32)"),
        ));
    }
    Ok(out)
}

/// One point: a sequence or array of 3 finite numbers.
pub fn point(obj: &Bound<'_, PyAny>, field: &str) -> PyResult<Vec3> {
    let py = obj.py();
    let np = numpy::get_array_module(py)?;
    let flat = np
        .call_method1("asarray", (obj, "float64"))
        .and_then(|a| a.call_method1("reshape", (-1,)))
        .map_err(|e| bad_array(py, field, format!("`{field}` is not a point: {e}")))?;
    let a = flat.cast_into::<PyArray1<f64>>()?.readonly();
    let v = a.as_slice()?;
    match v {
        [x, y, z] => {
            let p = Vec3::new(*x as f32, *y as f32, *z as f32);
            if p.is_finite() {
                Ok(p)
            } else {
                Err(bad_array(
                    py,
                    field,
                    format!("`{field}` must be finite, got {p}"),
                ))
            }
        }
        _ => Err(bad_array(
            py,
            field,
            format!("`{field}` must be 3 numbers (x, y, z), got {}", v.len()),
        )),
    }
}

/// An `(m, k)` array of vertex indices (any integer dtype), `k` one of `columns`: its rows,
/// each index checked to be in `0..=u32::MAX`. Returns the rows flattened and `k`.
pub fn indices(
    obj: &Bound<'_, PyAny>,
    field: &str,
    columns: &[usize],
) -> PyResult<(Vec<u32>, usize)> {
    let py = obj.py();
    let array = as_array(obj, field, columns, "vertex indices from 0")?;
    let k = array.shape()[1];
    let kind = array.dtype().kind();
    let integers = kind == b'i' || kind == b'u';
    // An empty float array (`np.zeros((0, 3))`) has no index to lose.
    let empty = kind == b'f' && array.len() == 0;
    if !(integers || empty) {
        return Err(bad_array(
            py,
            field,
            format!(
                "`{field}` must hold integers (vertex indices), got dtype kind '{}'",
                kind as char
            ),
        ));
    }
    let np = numpy::get_array_module(py)?;
    let converted = np.call_method1("ascontiguousarray", (&array, "int64"))?;
    let a = converted.cast_into::<PyArray2<i64>>()?.readonly();
    let flat = a.as_slice()?;
    let mut out = Vec::with_capacity(flat.len());
    for (i, &v) in flat.iter().enumerate() {
        let index = u32::try_from(v).map_err(|_| {
            bad_array(
                py,
                field,
                format!("`{field}` row {} holds {v}: indices are from 0", i / k),
            )
        })?;
        out.push(index);
    }
    Ok((out, k))
}

/// Rows of `[u32; 3]` from flat indices (`k` = 3).
pub fn triples(flat: &[u32]) -> Vec<[u32; 3]> {
    flat.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect()
}

/// Rows of `[u32; 4]` from flat indices (`k` = 4).
pub fn quads(flat: &[u32]) -> Vec<[u32; 4]> {
    flat.chunks_exact(4)
        .map(|c| [c[0], c[1], c[2], c[3]])
        .collect()
}

/// Positions as a new float64 `(n, 3)` array (exact: every float32 is a float64).
pub fn positions_out<'py, P: Copy + Into<Vec3>>(
    py: Python<'py>,
    positions: &[P],
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let flat: Vec<f64> = positions
        .iter()
        .flat_map(|&p| {
            let p: Vec3 = p.into();
            [f64::from(p.x), f64::from(p.y), f64::from(p.z)]
        })
        .collect();
    let array = Array2::from_shape_vec((positions.len(), 3), flat)
        .map_err(|e| crate::errors::bug(py, format!("a positions array: {e}")))?;
    Ok(PyArray2::from_owned_array(py, array))
}

/// Index rows as a new int64 `(m, K)` array.
pub fn indices_out<'py, const K: usize>(
    py: Python<'py>,
    rows: &[[u32; K]],
) -> PyResult<Bound<'py, PyArray2<i64>>> {
    let flat: Vec<i64> = rows
        .iter()
        .flat_map(|r| r.iter().map(|&i| i64::from(i)))
        .collect();
    let array = Array2::from_shape_vec((rows.len(), K), flat)
        .map_err(|e| crate::errors::bug(py, format!("an index array: {e}")))?;
    Ok(PyArray2::from_owned_array(py, array))
}

/// A per-vertex field as a new float64 `(n,)` array.
pub fn field_out<'py>(py: Python<'py>, values: &[f32]) -> Bound<'py, PyArray1<f64>> {
    PyArray1::from_owned_array(py, Array1::from_iter(values.iter().map(|&v| f64::from(v))))
}

/// A vector as a new float64 `(3,)` array.
pub fn vec3_out(py: Python<'_>, v: Vec3) -> Bound<'_, PyArray1<f64>> {
    PyArray1::from_slice(py, &v.to_array().map(f64::from))
}
