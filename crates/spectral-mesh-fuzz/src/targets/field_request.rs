//! Field requests as the faces send them (`analysis::FieldRequest` through serde): the
//! web app's JSON bodies (`serde_json`) when the first byte is even, an experiment file's
//! `[field]` table (`toml`) when it is odd. A parsed request is asked for its kind, pairs,
//! source and time, and validated (`FieldRequest::validate`, which must not panic); a
//! valid one must survive a JSON and a TOML round trip unchanged (a request saved by one
//! face replays in another). TOML has no integer above `i64::MAX`: writing such a `k`,
//! vertex or index (valid here, refused later against the mesh) may fail, cleanly.

use spectral_mesh::analysis::FieldRequest;

/// True when `v` holds an integer TOML cannot write (above `i64::MAX`).
fn has_huge_integer(v: &serde_json::Value) -> bool {
    match v {
        serde_json::Value::Number(n) => n.as_u64().is_some_and(|u| u > i64::MAX as u64),
        serde_json::Value::Array(a) => a.iter().any(has_huge_integer),
        serde_json::Value::Object(m) => m.values().any(has_huge_integer),
        _ => false,
    }
}

/// Runs one input of the target (what libFuzzer calls, and what the seed replay calls).
pub fn run(data: &[u8]) {
    let Some((&b, rest)) = data.split_first() else {
        return;
    };
    let Ok(text) = std::str::from_utf8(rest) else {
        return;
    };
    let parsed: Option<FieldRequest> = if b % 2 == 0 {
        serde_json::from_str(text).ok()
    } else {
        toml::from_str(text).ok()
    };
    let Some(r) = parsed else {
        return;
    };
    let _ = (
        r.kind(),
        r.eigenpairs(),
        r.source(),
        r.uses_source(),
        r.time(),
    );
    if r.validate().is_err() {
        return;
    }
    let json = serde_json::to_string(&r)
        .unwrap_or_else(|e| panic!("valid request {r:?} does not write as JSON: {e}"));
    let back: FieldRequest = serde_json::from_str(&json)
        .unwrap_or_else(|e| panic!("JSON {json} of a valid request does not read back: {e}"));
    assert_eq!(back, r, "JSON round trip of {json}");
    let toml_text = match toml::to_string(&r) {
        Ok(t) => t,
        Err(_)
            if has_huge_integer(&serde_json::from_str(&json).expect("JSON reads as a value")) =>
        {
            return;
        }
        Err(e) => panic!("valid request {r:?} does not write as TOML: {e}"),
    };
    let back: FieldRequest = toml::from_str(&toml_text)
        .unwrap_or_else(|e| panic!("TOML {toml_text} of a valid request does not read back: {e}"));
    assert_eq!(back, r, "TOML round trip of {toml_text}");
}
