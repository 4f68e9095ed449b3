//! Tests of the filters and the expression language.

use super::*;

fn ev(src: &str, s: f64) -> f64 {
    Expr::parse(src, &["t"]).unwrap().eval(s, &[0.5])
}

#[test]
fn expression_precedence_and_functions() {
    assert_eq!(ev("1 + 2 * 3", 0.0), 7.0);
    assert_eq!(ev("-s^2", 3.0), -9.0);
    assert_eq!(ev("2^3^2", 0.0), 512.0);
    assert_eq!(ev("(1+2)*3", 0.0), 9.0);
    assert_eq!(ev("2*-s", 3.0), -6.0);
    assert!((ev("exp(-s*t)/s", 2.0) - (-1.0f64).exp() / 2.0).abs() < 1e-15);
    assert_eq!(ev("max(s, 1) + min(s, 1) + pow(2, 3)", 4.0), 13.0);
    assert_eq!(ev("1e-3 * 1E3", 0.0), 1.0);
    assert!(
        (ev(
            "sqrt(abs(-4)) + log(exp(1)) + tanh(0) + sin(0) + cos(0)",
            0.0
        ) - 4.0)
            .abs()
            < 1e-15
    );
}

#[test]
fn parse_errors_give_positions() {
    let e = Expr::parse("s + * 2", &[]).unwrap_err();
    assert!(
        matches!(e, FilterError::Expression { position: 4, .. }),
        "{e}"
    );
    let e = Expr::parse("exp(s", &[]).unwrap_err();
    assert!(
        matches!(e, FilterError::Expression { position: 5, .. }),
        "{e}"
    );
    let e = Expr::parse("foo(s)", &[]).unwrap_err();
    assert!(e.to_string().contains("unknown function 'foo'"), "{e}");
    let e = Expr::parse("s * q", &[]).unwrap_err();
    assert!(
        matches!(e, FilterError::Expression { position: 4, .. }),
        "{e}"
    );
    assert!(Expr::parse("", &[]).is_err());
    assert!(Expr::parse("(s))", &[]).is_err());
    assert!(Expr::parse("pow(s)", &[]).is_err());
}

#[test]
fn nesting_and_size_limits() {
    let nested = |d: usize| format!("{}s{}", "(".repeat(d), ")".repeat(d));
    // expr() itself is one level, each parenthesis one more.
    assert!(Expr::parse(&nested(MAX_EXPR_NESTING - 1), &[]).is_ok());
    let e = Expr::parse(&nested(MAX_EXPR_NESTING), &[]).unwrap_err();
    assert!(e.to_string().contains("nested too deeply"), "{e}");
    let e = Expr::parse(&format!("{}s", "-".repeat(100)), &[]).unwrap_err();
    assert!(e.to_string().contains("nested too deeply"), "{e}");
    // n terms make 2n - 1 nodes.
    let sum = |n: usize| vec!["s"; n].join("+");
    assert!(Expr::parse(&sum(MAX_EXPR_NODES.div_ceil(2)), &[]).is_ok());
    let e = Expr::parse(&sum(MAX_EXPR_NODES.div_ceil(2) + 1), &[]).unwrap_err();
    assert!(e.to_string().contains("expression too long"), "{e}");
    assert!(format!("custom-w:{}", sum(2000)).parse::<Filter>().is_err());
}

#[test]
fn filter_text_round_trip() {
    for t in [
        "diffusion:t=0.25",
        "commute",
        "biharmonic",
        "mix:a=0.3,t=0.7",
        "poly:p=2",
        "band:1,3",
        "custom-w:exp(-s*t)/s;t=0.1",
        "custom-phi:s^2",
    ] {
        let f: Filter = t.parse().unwrap();
        let g: Filter = f.to_string().parse().unwrap();
        assert_eq!(f, g, "{t}");
    }
    assert_eq!(
        "heat".parse::<Filter>().unwrap(),
        Filter::Diffusion { t: 0.5 }
    );
    for bad in [
        "diffusion:t=-1",
        "mix:a=2",
        "diffusion:x=1",
        "nonsense",
        "custom-w:s*q",
        "poly",
    ] {
        assert!(bad.parse::<Filter>().is_err(), "{bad}");
    }
}

#[test]
fn weights_skip_zero_and_refuse_negative() {
    let ev = [1e-14, 1.0, 2.0, 3.0];
    let w = Filter::Biharmonic.weights(&ev).unwrap();
    assert_eq!(w, vec![0.0, 1.0, 0.25, 1.0 / 9.0]);
    let f: Filter = "custom-w:2 - s".parse().unwrap();
    match f.weights(&ev).unwrap_err() {
        FilterError::NotPositive { index, value, .. } => {
            assert_eq!(index, 2);
            assert_eq!(value, 2.0);
        }
        e => panic!("{e}"),
    }
    let phi: Filter = "custom-phi:s^2".parse().unwrap();
    assert_eq!(phi.weights(&ev).unwrap(), w);
    let band = Filter::BandSuppression { indices: vec![2] };
    assert_eq!(band.weights(&ev).unwrap(), vec![0.0, 1.0, 0.0, 1.0]);
    assert!(
        Filter::BandSuppression { indices: vec![9] }
            .weights(&ev)
            .is_err()
    );
    assert!(Filter::CommuteTime.weights(&[0.0, 0.0]).is_err());
}
