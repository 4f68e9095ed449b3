//! Python objects to and from `serde_json::Value`: requests arrive as Python dicts (the
//! library's serde form) and reports leave as dicts, without the `json` module (which
//! would cost the package's import time).

use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};
use serde_json::{Map, Number, Value};

use crate::errors::Failure;

/// A Python value as JSON: `None`, bools, integers (NumPy's too), finite floats, strings,
/// lists, tuples and dicts with string keys. `path` names the value in errors.
pub fn from_py(obj: &Bound<'_, PyAny>, path: &str) -> Result<Value, Failure> {
    if obj.is_none() {
        return Ok(Value::Null);
    }
    if let Ok(b) = obj.cast::<PyBool>() {
        return Ok(Value::Bool(b.is_true()));
    }
    if obj.is_instance_of::<PyInt>() {
        return int(obj, path);
    }
    if obj.is_instance_of::<PyFloat>() {
        return float(obj, path);
    }
    if let Ok(s) = obj.cast::<PyString>() {
        return Ok(Value::String(s.to_string()));
    }
    if let Ok(d) = obj.cast::<PyDict>() {
        let mut map = Map::new();
        for (k, v) in d.iter() {
            let key = k
                .cast::<PyString>()
                .map_err(|_| Failure::value(format!("{path}: keys must be strings")))?
                .to_string();
            let sub = format!("{path}.{key}");
            map.insert(key, from_py(&v, sub.trim_start_matches('.'))?);
        }
        return Ok(Value::Object(map));
    }
    if obj.is_instance_of::<PyList>() || obj.is_instance_of::<PyTuple>() {
        let mut out = Vec::new();
        for (i, v) in obj
            .try_iter()
            .map_err(|e| Failure::value(e.to_string()))?
            .enumerate()
        {
            let v = v.map_err(|e| Failure::value(e.to_string()))?;
            out.push(from_py(&v, &format!("{path}[{i}]"))?);
        }
        return Ok(Value::Array(out));
    }
    // NumPy scalars: integers expose __index__, floats __float__.
    if obj.hasattr("__index__").unwrap_or(false) {
        return int(obj, path);
    }
    if obj.hasattr("__float__").unwrap_or(false) && !obj.hasattr("__len__").unwrap_or(false) {
        return float(obj, path);
    }
    let type_name = obj
        .get_type()
        .name()
        .map(|n| n.to_string())
        .unwrap_or_else(|_| "?".into());
    Err(Failure::value(format!(
        "{path}: a value of type {type_name} cannot be part of a request"
    )))
}

fn int(obj: &Bound<'_, PyAny>, path: &str) -> Result<Value, Failure> {
    if let Ok(i) = obj.extract::<i64>() {
        return Ok(Value::Number(i.into()));
    }
    if let Ok(u) = obj.extract::<u64>() {
        return Ok(Value::Number(u.into()));
    }
    Err(Failure::value(format!("{path}: integer out of range")))
}

fn float(obj: &Bound<'_, PyAny>, path: &str) -> Result<Value, Failure> {
    let x: f64 = obj
        .extract()
        .map_err(|e| Failure::value(format!("{path}: {e}")))?;
    Number::from_f64(x)
        .map(Value::Number)
        .ok_or_else(|| Failure::value(format!("{path} = {x}: must be a finite number")))
}

/// A JSON value as Python objects (dicts, lists, ints, floats, strings, None).
pub fn to_py<'py>(py: Python<'py>, v: &Value) -> PyResult<Bound<'py, PyAny>> {
    Ok(match v {
        Value::Null => py.None().into_bound(py),
        Value::Bool(b) => PyBool::new(py, *b).to_owned().into_any(),
        Value::Number(n) => {
            if let Some(i) = n.as_i64() {
                i.into_pyobject(py)?.into_any()
            } else if let Some(u) = n.as_u64() {
                u.into_pyobject(py)?.into_any()
            } else {
                n.as_f64().unwrap_or(f64::NAN).into_pyobject(py)?.into_any()
            }
        }
        Value::String(s) => PyString::new(py, s).into_any(),
        Value::Array(a) => {
            let items = a
                .iter()
                .map(|x| to_py(py, x))
                .collect::<PyResult<Vec<_>>>()?;
            PyList::new(py, items)?.into_any()
        }
        Value::Object(o) => {
            let d = PyDict::new(py);
            for (k, x) in o {
                d.set_item(k, to_py(py, x)?)?;
            }
            d.into_any()
        }
    })
}
