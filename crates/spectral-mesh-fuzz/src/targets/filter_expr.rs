//! The custom-filter expression language (`spectral::filters::Expr::parse`, with the
//! parameters `t` and `a`) and its evaluation at several points. A parsed expression
//! evaluates to the same bits (or NaN) when put in parentheses (unless that one more
//! level passes the nesting limit), and works as a
//! `custom-w` / `custom-phi` filter whose text parses back.

use std::collections::BTreeMap;

use spectral_mesh::spectral::filters::{CustomKind, Expr, Filter};

const POINTS: [f64; 8] = [0.0, -0.0, 1e-300, 0.5, 1.0, 3.0, 1e300, -2.0];

fn same(x: f64, y: f64) -> bool {
    x.to_bits() == y.to_bits() || (x.is_nan() && y.is_nan())
}

/// Runs one input of the target (what libFuzzer calls, and what the seed replay calls).
pub fn run(data: &[u8]) {
    let Ok(src) = std::str::from_utf8(data) else {
        return;
    };
    let names = ["t", "a"];
    let values = [0.5, 2.0];
    let Ok(e) = Expr::parse(src, &names) else {
        return;
    };
    let wrapped = match Expr::parse(&format!("({src})"), &names) {
        Ok(w) => w,
        // One more level may pass the nesting limit.
        Err(err) if err.to_string().contains("nested too deeply") => return,
        Err(err) => panic!("({src}) does not parse although {src} does: {err}"),
    };
    for s in POINTS {
        let (x, y) = (e.eval(s, &values), wrapped.eval(s, &values));
        assert!(same(x, y), "{src} = {x} but ({src}) = {y} at s = {s}");
    }
    let params: BTreeMap<String, f64> = names
        .iter()
        .zip(values)
        .map(|(n, v)| (n.to_string(), v))
        .collect();
    for kind in [CustomKind::Weight, CustomKind::Phi] {
        let f = Filter::custom(src, params.clone(), kind)
            .unwrap_or_else(|err| panic!("{src} parses as an Expr but not as a filter: {err}"));
        let text = f.to_string();
        let g: Filter = text
            .parse()
            .unwrap_or_else(|err| panic!("{text:?} does not parse back: {err}"));
        for s in POINTS {
            assert!(
                same(f.weight(s), g.weight(s)),
                "{text}: weight changed at {s}"
            );
        }
    }
}
