//! `io::read_mesh_from_bytes` on raw bytes named `fuzz.ply` (header and body as the fuzzer
//! writes them; the seeds are ASCII PLY files).
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    spectral_mesh_fuzz::read_and_check(data, "fuzz.ply");
});
