//! Experiment files (`experiments::file::ExperimentFile::parse`, the TOML files that
//! `spectral-mesh run` replays and the faces save). An error names the file (`e.toml`)
//! first, and a line that exists when it names one. A parsed file answers its accessors
//! (`laplacian`, `request`, `harmonic_constraints`, `normalize`) without error or panic,
//! and `to_toml` writes text that parses back to the same file.

use spectral_mesh::experiments::file::ExperimentFile;

/// Runs one input of the target (what libFuzzer calls, and what the seed replay calls).
pub fn run(data: &[u8]) {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let f = match ExperimentFile::parse(text, "e.toml") {
        Ok(f) => f,
        Err(e) => {
            let msg = e.to_string();
            assert!(
                msg.starts_with("e.toml"),
                "error does not name the file: {msg}"
            );
            if let Some(rest) = msg.strip_prefix("e.toml:")
                && let Some(line) = rest.split(':').next().and_then(|l| l.parse::<usize>().ok())
            {
                let lines = text.lines().count().max(1);
                assert!(
                    line >= 1 && line <= lines + 1,
                    "error names line {line} of a {lines}-line file: {msg}"
                );
            }
            return;
        }
    };
    f.laplacian()
        .unwrap_or_else(|e| panic!("a parsed file has a bad laplacian: {e}"));
    let _ = f.normalize();
    if f.experiment == "harmonic" {
        f.harmonic_constraints()
            .unwrap_or_else(|e| panic!("a parsed harmonic file has bad constraints: {e}"));
    } else {
        let r = f
            .request()
            .unwrap_or_else(|| panic!("a parsed {} file has no request", f.experiment));
        r.validate()
            .unwrap_or_else(|e| panic!("the request of a parsed file is invalid: {e}"));
    }
    let written = f
        .to_toml()
        .unwrap_or_else(|e| panic!("a parsed file does not write: {e}"));
    let back = ExperimentFile::parse(&written, "rt.toml")
        .unwrap_or_else(|e| panic!("written file does not parse back: {e}\n{written}"));
    assert_eq!(back, f, "round trip through\n{written}");
}
