//! One module per fuzz target: `run(data)` feeds one input to a library entry point and
//! asserts what the library promises. libFuzzer calls it from `fuzz/fuzz_targets/NAME.rs`;
//! the tests of this crate call it on every committed seed and regression input.

pub mod basis_npz;
pub mod constraints;
pub mod detect_format;
pub mod experiment_file;
pub mod field_request;
pub mod field_text;
pub mod filter;
pub mod filter_expr;
pub mod perturb_spec;
pub mod pipeline_eigen;
pub mod pipeline_points;
pub mod read_obj;
pub mod read_off;
pub mod read_ply_ascii;
pub mod read_ply_binary;
pub mod read_points;
pub mod read_stl_ascii;
pub mod read_stl_binary;
pub mod shape;
pub mod validate_repair;
pub mod web_body;

/// A target's entry: one input in, a panic on a broken promise.
pub type Run = fn(&[u8]);

/// Every target: its name (the folder of its seeds, `fuzz/seeds/NAME`) and its entry.
pub const ALL: &[(&str, Run)] = &[
    ("basis_npz", basis_npz::run),
    ("constraints", constraints::run),
    ("detect_format", detect_format::run),
    ("experiment_file", experiment_file::run),
    ("field_request", field_request::run),
    ("field_text", field_text::run),
    ("filter", filter::run),
    ("filter_expr", filter_expr::run),
    ("perturb_spec", perturb_spec::run),
    ("pipeline_eigen", pipeline_eigen::run),
    ("pipeline_points", pipeline_points::run),
    ("read_obj", read_obj::run),
    ("read_off", read_off::run),
    ("read_ply_ascii", read_ply_ascii::run),
    ("read_ply_binary", read_ply_binary::run),
    ("read_points", read_points::run),
    ("read_stl_ascii", read_stl_ascii::run),
    ("read_stl_binary", read_stl_binary::run),
    ("shape", shape::run),
    ("validate_repair", validate_repair::run),
    ("web_body", web_body::run),
];
