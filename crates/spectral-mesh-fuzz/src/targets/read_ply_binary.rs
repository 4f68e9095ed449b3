//! Binary PLY payloads: the first bytes choose a well-formed header (byte order, the types
//! of the coordinates, of the face list count and indices, colours, an extra element,
//! element counts) and the rest of the input is the binary payload, so the fuzzer
//! explores the payload decoding instead of spelling headers. With the top bit of the
//! first byte set, the rest of the input is read as a whole file instead.

const SCALARS: [&str; 8] = [
    "float", "double", "uchar", "char", "short", "ushort", "int", "uint",
];
const COUNTS: [&str; 4] = ["uchar", "ushort", "uint", "char"];
const INDICES: [&str; 6] = ["int", "uint", "short", "ushort", "uchar", "char"];

/// Runs one input of the target (what libFuzzer calls, and what the seed replay calls).
pub fn run(data: &[u8]) {
    if data.first().is_some_and(|&b| b & 0x80 != 0) {
        crate::read_and_check(&data[1..], "fuzz.ply");
        return;
    }
    if data.len() < 4 {
        return;
    }
    let (h, payload) = data.split_at(4);
    let big = h[0] & 1 != 0;
    let colours = h[0] & 2 != 0;
    let extra = h[0] & 4 != 0;
    let name = if h[0] & 8 != 0 {
        "vertex_index"
    } else {
        "vertex_indices"
    };
    let coord = SCALARS[usize::from(h[1] & 7)];
    let count = COUNTS[usize::from((h[1] >> 3) & 3)];
    let index = INDICES[usize::from(h[1] >> 5) % INDICES.len()];
    let nv = usize::from(h[2]);
    let nf = usize::from(h[3]);
    let mut file = format!(
        "ply\nformat binary_{}_endian 1.0\nelement vertex {nv}\n",
        if big { "big" } else { "little" }
    );
    for c in ["x", "y", "z"] {
        file.push_str(&format!("property {coord} {c}\n"));
    }
    if colours {
        for c in ["red", "green", "blue"] {
            file.push_str(&format!("property uchar {c}\n"));
        }
    }
    file.push_str(&format!(
        "element face {nf}\nproperty list {count} {index} {name}\n"
    ));
    if extra {
        file.push_str("element edge 1\nproperty int vertex1\nproperty int vertex2\n");
    }
    file.push_str("end_header\n");
    let mut bytes = file.into_bytes();
    bytes.extend_from_slice(payload);
    crate::read_and_check(&bytes, "fuzz.ply");
}
