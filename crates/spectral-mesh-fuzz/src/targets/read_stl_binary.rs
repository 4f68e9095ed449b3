//! Binary STL: the input after the first byte is the facet records (50 bytes each); the
//! first byte chooses the 80-byte header (zeros, or text starting with `solid`, which
//! must not make it pass for ASCII) and whether the triangle count matches the records
//! (the usual case) or is taken from the input (a truncated or padded file). With the top
//! bit set, the input is read as a whole file instead.

/// Runs one input of the target (what libFuzzer calls, and what the seed replay calls).
pub fn run(data: &[u8]) {
    let Some((&mode, rest)) = data.split_first() else {
        return;
    };
    if mode & 0x80 != 0 {
        crate::read_and_check(rest, "fuzz.stl");
        return;
    }
    let mut file = vec![0u8; 80];
    if mode & 1 != 0 {
        let text = b"solid facet vertex endsolid outer loop";
        file[..text.len()].copy_from_slice(text);
    }
    let (count, records) = if mode & 2 != 0 && rest.len() >= 4 {
        let c = u32::from_le_bytes([rest[0], rest[1], rest[2], rest[3]]);
        (c, &rest[4..])
    } else {
        let k = rest.len() / 50;
        (u32::try_from(k).unwrap_or(u32::MAX), &rest[..k * 50])
    };
    file.extend_from_slice(&count.to_le_bytes());
    file.extend_from_slice(records);
    let name = if mode & 4 != 0 { "fuzz" } else { "fuzz.stl" };
    crate::read_and_check(&file, name);
}
