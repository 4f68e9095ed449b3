//! `io::read_mesh_from_bytes` on raw bytes named `fuzz.stl` (the seeds are ASCII STL files;
//! a binary one is recognised by its size).
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    spectral_mesh_fuzz::read_and_check(data, "fuzz.stl");
});
