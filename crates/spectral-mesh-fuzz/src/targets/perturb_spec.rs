//! Perturbation specs (`perturb::spec::parse_perturbation`, as typed on the command line
//! or stored in a study file): the canonical text (`Display`) parses back to a spec that
//! prints the same. Applying specs is not fuzzed here (a spec may legitimately ask for
//! up to 10^9 vertices; see RELIABILITY.md).

use spectral_mesh::perturb::spec::parse_perturbation;

/// Runs one input of the target (what libFuzzer calls, and what the seed replay calls).
pub fn run(data: &[u8]) {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let Ok(spec) = parse_perturbation(text) else {
        return;
    };
    let printed = spec.to_string();
    let again = parse_perturbation(&printed)
        .unwrap_or_else(|e| panic!("{text:?} printed as {printed:?}, which fails: {e}"));
    assert_eq!(again.to_string(), printed, "printing is not stable");
}
