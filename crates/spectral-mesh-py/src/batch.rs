//! Shape collections (`spectral_mesh.batch`): the library's per-shape job
//! ([`spectral_mesh::batch::process_one`]) and its helpers for the pure-Python layer,
//! which runs the jobs on a local process pool or a Dask cluster. Records cross as JSON
//! text (small: a few hundred bytes), so that a Dask task returns plain Python data.
//!
//! Threads: every job of a process runs inside one rayon pool per thread count, made on
//! first use and shared, so that the jobs a Dask worker runs at once on its `nthreads`
//! threads share `nthreads` threads of ours instead of each starting its own pool.

use std::collections::HashMap;
use std::path::PathBuf;
use std::sync::{Arc, Mutex, OnceLock};

use pyo3::prelude::*;
use spectral_mesh::batch::{
    BatchInput, BatchParams, BatchRecord, JobOptions, Schedule, prepare_output, process_one,
    remove_stale_temporaries, resolve_inputs, write_summary,
};
use spectral_mesh_render::Thumbnails;

use crate::errors::Failure;
use crate::run::run;

/// The shared pool of `threads` threads.
pub(crate) fn pool(threads: usize) -> Result<Arc<rayon::ThreadPool>, Failure> {
    static POOLS: OnceLock<Mutex<HashMap<usize, Arc<rayon::ThreadPool>>>> = OnceLock::new();
    let mut pools = POOLS
        .get_or_init(Mutex::default)
        .lock()
        .unwrap_or_else(|p| p.into_inner());
    if let Some(p) = pools.get(&threads) {
        return Ok(p.clone());
    }
    let p = Arc::new(
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .thread_name(|i| format!("spectral-mesh-batch-{i}"))
            .build()
            .map_err(|e| Failure::Internal(format!("cannot start {threads} threads: {e}")))?,
    );
    pools.insert(threads, p.clone());
    Ok(p)
}

/// The parameters from the Python layer's JSON (keys of [`BatchParams`]; `hks`, `wks`,
/// `adf` as text `auto:N` or `t1,t2,...`), validated: `(canonical JSON, hash)`.
#[pyfunction]
pub fn batch_params(py: Python<'_>, json: &str) -> PyResult<(String, String)> {
    parse_params(json).map_err(|e| e.into_pyerr(py))
}

fn parse_params(json: &str) -> Result<(String, String), Failure> {
    let mut value: serde_json::Value =
        serde_json::from_str(json).map_err(|e| Failure::value(format!("parameters: {e}")))?;
    if let Some(map) = value.as_object_mut() {
        if let Some(t) = map.get("tolerance").and_then(serde_json::Value::as_f64) {
            map.insert(
                "tolerance".to_string(),
                serde_json::json!(crate::tolerance_of(t)?),
            );
        }
        for key in ["hks", "wks", "adf"] {
            if let Some(serde_json::Value::String(s)) = map.get(key) {
                let schedule: Schedule = s
                    .parse()
                    .map_err(|e: String| Failure::value(format!("{key}: {e}")))?;
                let v = serde_json::to_value(&schedule)
                    .map_err(|e| Failure::Internal(e.to_string()))?;
                map.insert(key.to_string(), v);
            }
        }
    }
    let params: BatchParams =
        serde_json::from_value(value).map_err(|e| Failure::value(format!("parameters: {e}")))?;
    params
        .validate()
        .map_err(|e| Failure::value(e.to_string()))?;
    let canonical = serde_json::to_string(&params).map_err(|e| Failure::Internal(e.to_string()))?;
    Ok((canonical, params.hash()))
}

/// The shapes of the inputs (files, folders, globs, `@manifest`s): `[(path, name)]`.
#[pyfunction]
pub fn batch_inputs(py: Python<'_>, specs: Vec<String>) -> PyResult<Vec<(String, String)>> {
    run(py, move |_| {
        let list = resolve_inputs(&specs).map_err(|e| Failure::value(e.to_string()))?;
        Ok(list
            .into_iter()
            .map(|i| (i.path.display().to_string(), i.name))
            .collect())
    })
}

/// Makes the output folder ready (see `prepare_output`) and removes the temporary files
/// of an interrupted run; returns how many were removed.
#[pyfunction]
pub fn batch_prepare(py: Python<'_>, out: PathBuf, force: bool) -> PyResult<usize> {
    run(py, move |_| {
        prepare_output(&out, force).map_err(|e| Failure::value(e.to_string()))?;
        Ok(remove_stale_temporaries(&out))
    })
}

/// One shape: its record as JSON text. Runs with the GIL released inside the shared pool
/// of `threads` threads (0: the library's global pool); never raises for a bad shape (its
/// record says why), only for bad arguments or Ctrl-C.
#[pyfunction]
#[pyo3(signature = (path, name, params, out, threads, retry_failed=false))]
pub fn batch_one(
    py: Python<'_>,
    path: PathBuf,
    name: String,
    params: &str,
    out: PathBuf,
    threads: usize,
    retry_failed: bool,
) -> PyResult<String> {
    let params: BatchParams = serde_json::from_str(params)
        .map_err(|e| Failure::value(format!("parameters: {e}")).into_pyerr(py))?;
    run(py, move |token| {
        let input = BatchInput { path, name };
        let thumbnails = Thumbnails;
        let options = JobOptions {
            threads: 0,
            thumbnailer: Some(&thumbnails),
            retry_failed,
            cancel: token.clone(),
            progress: None,
        };
        let job = || process_one(&input, &params, &out, &options);
        let record = if threads > 0 {
            pool(threads)?.install(job)
        } else {
            job()
        };
        serde_json::to_string(&record).map_err(|e| Failure::Internal(e.to_string()))
    })
}

/// A failed record (a job that could not run: its worker died), as JSON text.
#[pyfunction]
pub fn batch_failed(
    py: Python<'_>,
    path: String,
    name: String,
    params_hash: String,
    message: String,
) -> PyResult<String> {
    let r = BatchRecord::failed(&name, &path, &params_hash, message);
    serde_json::to_string(&r).map_err(|e| Failure::Internal(e.to_string()).into_pyerr(py))
}

/// Writes `summary.csv` and `summary.parquet` from the records (JSON texts); returns their
/// paths.
#[pyfunction]
pub fn batch_summary(
    py: Python<'_>,
    out: PathBuf,
    records: Vec<String>,
) -> PyResult<(String, String)> {
    run(py, move |_| {
        let records = records
            .iter()
            .map(|r| serde_json::from_str::<BatchRecord>(r))
            .collect::<Result<Vec<_>, _>>()
            .map_err(|e| Failure::value(format!("a record: {e}")))?;
        let [csv, pq] = write_summary(&out, &records).map_err(|e| Failure::value(e.to_string()))?;
        Ok((csv.display().to_string(), pq.display().to_string()))
    })
}
