//! A glTF of one primitive built from fuzz bytes, for the `gltf_accessors` target and its replay in
//! tests/fuzz_corpus.rs. The bytes choose the numbers that decide what the accessors claim and
//! what backs them (counts, offsets, strides, component types, view and buffer lengths, sparse
//! blocks, the primitive's mode) while the JSON around them stays valid: a byte-level mutator on
//! glTF text spends nearly all its time on syntax errors and rarely meets a count that disagrees
//! with its buffer, the class that once made a 1 KB file allocate 3 GB.

/// Reads the fuzz input as a stream of little-endian numbers; past its end, zeros.
struct Numbers<'a> {
    data: &'a [u8],
}

impl Numbers<'_> {
    fn u32(&mut self) -> u32 {
        let mut bytes = [0u8; 4];
        let n = self.data.len().min(4);
        bytes[..n].copy_from_slice(&self.data[..n]);
        self.data = &self.data[n..];
        u32::from_le_bytes(bytes)
    }

    fn byte(&mut self) -> u8 {
        let (first, rest) = self.data.split_first().map_or((0, &[][..]), |(f, r)| (*f, r));
        self.data = rest;
        first
    }

    /// One of `choices`.
    fn pick<T: Copy>(&mut self, choices: &[T]) -> T {
        choices[self.byte() as usize % choices.len()]
    }

    /// A count or length: small values most of the time, anything up to `u32::MAX` otherwise.
    fn size(&mut self) -> u32 {
        match self.byte() % 4 {
            0 => self.u32(),
            1 => u32::from(self.byte()) << 20,
            _ => u32::from(self.byte()),
        }
    }
}

/// An accessor's JSON: `type`, on view `view` (or none), maybe sparse.
fn accessor(numbers: &mut Numbers, kind: &str, component_types: &[u32], views: usize, position: bool) -> String {
    let mut fields = vec![
        format!(r#""componentType": {}"#, numbers.pick(component_types)),
        format!(r#""count": {}"#, numbers.size()),
        format!(r#""type": "{kind}""#),
    ];
    if !numbers.byte().is_multiple_of(4) {
        fields.push(format!(r#""bufferView": {}"#, numbers.byte() as usize % views));
        fields.push(format!(r#""byteOffset": {}"#, numbers.size() & !3));
    }
    if position {
        fields.push(r#""min": [-1, -1, -1], "max": [1, 1, 1]"#.to_owned());
    }
    if numbers.byte().is_multiple_of(2) {
        fields.push(format!(
            r#""sparse": {{"count": {}, "indices": {{"bufferView": {}, "byteOffset": {}, "componentType": {}}}, "values": {{"bufferView": {}, "byteOffset": {}}}}}"#,
            numbers.size(),
            numbers.byte() as usize % views,
            numbers.size() & !3,
            numbers.pick(&[5121, 5123, 5125]),
            numbers.byte() as usize % views,
            numbers.size() & !3,
        ));
    }
    format!("{{{}}}", fields.join(", "))
}

/// The bytes of a valid triangle, which the buffer repeats: three f32 positions at 0, u16 indices
/// 0, 1, 2 at 36, u8 indices 0, 1, 2 at 44 (each padded to 4 bytes).
fn triangle_block() -> Vec<u8> {
    let positions: [f32; 9] = [0., 0., 0., 1., 0., 0., 0., 1., 0.];
    let mut block: Vec<u8> = positions.iter().flat_map(|f| f.to_le_bytes()).collect();
    block.extend([0u16, 1, 2, 0].iter().flat_map(|i| i.to_le_bytes()));
    block.extend([0u8, 1, 2, 0]);
    block
}

/// The name the glTF gives its buffer: a file beside it.
pub const BUFFER_FILE: &str = "input.bin";

/// The glTF JSON for `data` and the contents of its buffer file ([`BUFFER_FILE`]): a valid
/// triangle's bytes repeated, up to four views on them, and one primitive reading POSITION, maybe
/// NORMAL and TEXCOORD_0, and maybe indices.
pub fn gltf(data: &[u8]) -> (String, Vec<u8>) {
    let mut numbers = Numbers { data };
    let buffer_length = numbers.byte() as usize * 4;
    let buffer: Vec<u8> = triangle_block().into_iter().cycle().take(buffer_length).collect();
    let declared = if numbers.byte().is_multiple_of(8) { numbers.size() as usize } else { buffer_length };
    let view_count = 1 + numbers.byte() as usize % 4;
    let views: Vec<String> = (0..view_count)
        .map(|_| {
            let stride = match numbers.byte() % 4 {
                0 => format!(r#", "byteStride": {}"#, 4 + 4 * (numbers.byte() % 62)),
                _ => String::new(),
            };
            format!(r#"{{"buffer": 0, "byteOffset": {}, "byteLength": {}{stride}}}"#, numbers.size(), numbers.size())
        })
        .collect();
    let mut accessors = vec![accessor(&mut numbers, "VEC3", &[5126, 5126, 5123], view_count, true)];
    let mut attributes = vec![r#""POSITION": 0"#.to_owned()];
    if numbers.byte().is_multiple_of(2) {
        attributes.push(format!(r#""NORMAL": {}"#, accessors.len()));
        accessors.push(accessor(&mut numbers, "VEC3", &[5126], view_count, false));
    }
    if numbers.byte().is_multiple_of(2) {
        attributes.push(format!(r#""TEXCOORD_0": {}"#, accessors.len()));
        accessors.push(accessor(&mut numbers, "VEC2", &[5126, 5121, 5123], view_count, false));
    }
    let indices = if !numbers.byte().is_multiple_of(4) {
        accessors.push(accessor(&mut numbers, "SCALAR", &[5121, 5123, 5125], view_count, false));
        format!(r#", "indices": {}"#, accessors.len() - 1)
    } else {
        String::new()
    };
    let mode = numbers.pick(&[4, 4, 5, 6]);
    let json = format!(
        r#"{{"asset": {{"version": "2.0"}}, "scene": 0, "scenes": [{{"nodes": [0]}}], "nodes": [{{"mesh": 0}}],
"meshes": [{{"primitives": [{{"attributes": {{{}}}{indices}, "mode": {mode}}}]}}],
"buffers": [{{"uri": "{BUFFER_FILE}", "byteLength": {declared}}}],
"bufferViews": [{}], "accessors": [{}]}}"#,
        attributes.join(", "),
        views.join(", "),
        accessors.join(", ")
    );
    (json, buffer)
}
