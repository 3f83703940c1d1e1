//! One byte order for an OpenEXR header: its attributes sorted by name.
//!
//! The `exr` crate keeps the attributes it does not know (caustica's `caustica.*` text) in a
//! `HashMap` with a per-process random seed and writes them in its iteration order, so the same
//! image written twice gave two different files (same pixels, same attributes, shuffled header),
//! and a farm's merges could not be compared with `cmp` or a checksum. Sorting the attributes after
//! encoding makes equal images equal files. The header keeps its length, so the offset table and
//! pixel data after it are untouched.

/// Sorts the attributes of a single-part OpenEXR file's header by name, in place. Leaves other
/// files (multi-part, or not a header this reads to its end) unchanged.
pub fn sort_header_attributes(file: &mut [u8]) {
    const MAGIC: [u8; 4] = [0x76, 0x2f, 0x31, 0x01];
    const MULTIPART: u8 = 0x10; // bit 12 of the version field: byte 5, bit 4
    if file.len() < 8 || file[..4] != MAGIC || file[5] & MULTIPART != 0 {
        return;
    }
    let Some((attributes, end)) = attributes(file, 8) else { return };
    let mut sorted = attributes.clone();
    sorted.sort_by(|a, b| name(file, a).cmp(name(file, b)));
    let header: Vec<u8> = sorted.iter().flat_map(|r| file[r.clone()].to_vec()).collect();
    debug_assert_eq!(header.len(), end - 8);
    file[8..end].copy_from_slice(&header);
}

/// The byte ranges of the attributes from `start` (name, NUL, type, NUL, 4-byte little-endian
/// size, value) and where the NUL that ends the header is; None if the header runs off the end.
fn attributes(file: &[u8], start: usize) -> Option<(Vec<std::ops::Range<usize>>, usize)> {
    let mut at = start;
    let mut found = Vec::new();
    loop {
        if *file.get(at)? == 0 {
            return Some((found, at));
        }
        let name_end = at + file[at..].iter().position(|&b| b == 0)?;
        let type_end = name_end + 1 + file.get(name_end + 1..)?.iter().position(|&b| b == 0)?;
        let size_bytes: [u8; 4] = file.get(type_end + 1..type_end + 5)?.try_into().ok()?;
        let size = usize::try_from(i32::from_le_bytes(size_bytes)).ok()?;
        let end = (type_end + 5).checked_add(size).filter(|&e| e <= file.len())?;
        found.push(at..end);
        at = end;
    }
}

/// The name of the attribute whose bytes are `range`.
fn name<'a>(file: &'a [u8], range: &std::ops::Range<usize>) -> &'a [u8] {
    let bytes = &file[range.clone()];
    &bytes[..bytes.iter().position(|&b| b == 0).unwrap_or(bytes.len())]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn attribute(name: &str, kind: &str, value: &[u8]) -> Vec<u8> {
        let mut out = [name.as_bytes(), b"\0", kind.as_bytes(), b"\0"].concat();
        out.extend((value.len() as i32).to_le_bytes());
        out.extend(value);
        out
    }

    #[test]
    fn sorts_attributes_by_name_and_leaves_the_rest() {
        let head = [0x76, 0x2f, 0x31, 0x01, 2, 0, 0, 0];
        let (a, b, c) =
            (attribute("b", "string", b"xy"), attribute("a", "int", &[1, 0, 0, 0]), attribute("c", "string", b""));
        let mut file = [&head[..], &b, &c, &a, b"\0", b"pixels"].concat();
        sort_header_attributes(&mut file);
        assert_eq!(file, [&head[..], &b, &a, &c, b"\0", b"pixels"].concat());
    }

    #[test]
    fn leaves_multipart_and_cut_headers_alone() {
        let multipart =
            [&[0x76, 0x2f, 0x31, 0x01, 2, 0x10, 0, 0][..], &attribute("b", "t", b""), &attribute("a", "t", b""), b"\0"]
                .concat();
        let mut file = multipart.clone();
        sort_header_attributes(&mut file);
        assert_eq!(file, multipart);
        let cut = [&[0x76, 0x2f, 0x31, 0x01, 2, 0, 0, 0][..], &attribute("b", "t", b"abc")[..10]].concat();
        let mut file = cut.clone();
        sort_header_attributes(&mut file);
        assert_eq!(file, cut);
    }
}
