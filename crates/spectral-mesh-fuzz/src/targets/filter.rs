//! Filter text: `Filter::from_str`. A parsed filter prints (`Display`) as text that parses
//! back to a filter that prints the same, and its weights on several spectra (with zero,
//! tiny, huge and repeated eigenvalues) are either refused with an error or finite and
//! non-negative, one per eigenvalue, zero at the zero eigenvalues.

use spectral_mesh::spectral::filters::{Filter, ZERO_EIGENVALUE_EPS};

const SPECTRA: [&[f64]; 5] = [
    &[0.0, 1e-12, 0.3, 1.0, 1.0, 2.5, 40.0, 1e6],
    &[0.0, 0.0, 2.0],
    &[1e-300, 1e300],
    &[-1.0, 0.5, 3.0],
    &[],
];

/// Runs one input of the target (what libFuzzer calls, and what the seed replay calls).
pub fn run(data: &[u8]) {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let Ok(f) = text.parse::<Filter>() else {
        return;
    };
    let printed = f.to_string();
    let again: Filter = match printed.parse() {
        Ok(g) => g,
        Err(e) => panic!("{text:?} printed as {printed:?}, which does not parse: {e}"),
    };
    assert_eq!(again.to_string(), printed, "printing is not stable");
    for ev in SPECTRA {
        let _ = f.weight(ev.first().copied().unwrap_or(1.0));
        if let Ok(w) = f.weights(ev) {
            assert_eq!(w.len(), ev.len());
            let lmax = ev.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            for (x, l) in w.iter().zip(ev.iter()) {
                assert!(x.is_finite() && *x >= 0.0, "weight {x} at {l}");
                if l.abs() <= ZERO_EIGENVALUE_EPS * lmax {
                    assert_eq!(*x, 0.0, "a zero eigenvalue got weight {x}");
                }
            }
        }
    }
}
