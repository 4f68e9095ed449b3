//! libFuzzer entry of `spectral_mesh_fuzz::targets::pipeline_points` (what it checks is
//! documented there; `cargo test -p spectral-mesh-fuzz` replays this target's seeds).
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| spectral_mesh_fuzz::targets::pipeline_points::run(data));
