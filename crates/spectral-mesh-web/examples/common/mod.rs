//! What the web crate's examples share: reading `SPEC K ...` from the command line.

/// The arguments after the program name, the first read as a mesh spec (default `spec`)
/// and the second as a pair count (default `k`).
pub fn spec_and_k(spec: &str, k: usize) -> (Vec<String>, String, usize) {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let spec = args.first().cloned().unwrap_or_else(|| spec.into());
    let k = args
        .get(1)
        .map_or(k, |s| s.parse().expect("K: a whole number"));
    (args, spec, k)
}
