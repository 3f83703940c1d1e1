//! Checks on a glTF accessor before the gltf crate's readers touch it. The readers trust the
//! file: they panic on shapes they do not expect, and they allocate for as many elements as an
//! accessor's `count` claims. A sparse accessor without a buffer view is `count` zeros with a
//! few values replaced, so a 1 KB file claiming 2^28 positions that way made caustica allocate
//! 3 GB. Here every count is bounded by the bytes behind it before anything is read:
//!
//! - an accessor with a buffer view must fit in that view (offset, stride x (count - 1) and one
//!   element), and the view in its buffer's data;
//! - a sparse block's indices and values must fit in theirs, and its count in the accessor's;
//! - an accessor without a buffer view (zeros, maybe with sparse values) may describe no more
//!   bytes than the glTF and its buffers hold;
//! - all accessors read from one file may together decode to at most [`DECODE_FACTOR`] times
//!   that size: one large accessor reused by thousands of primitives would otherwise be copied
//!   thousands of times.

use std::rc::Rc;

use gltf::accessor::util::Item;
use gltf::accessor::{DataType, Dimensions, Iter};
use gltf::Accessor;

use crate::input_file::describe_bytes;

/// How many times its own size a glTF may decode to. Real files decode to about their size (each
/// accessor read once, or a few times when primitives share vertices).
pub(super) const DECODE_FACTOR: u64 = 64;

/// What reading accessors from one glTF may still allocate.
pub(super) struct AccessorLimits<'b> {
    buffers: &'b [Rc<Vec<u8>>],
    /// Bytes of the glTF file and all its buffers.
    file_bytes: u64,
    /// Bytes the accessors admitted so far decode to.
    decoded: u64,
}

impl<'b> AccessorLimits<'b> {
    /// Limits for a glTF of `file_bytes` bytes (the file itself) whose buffers are `buffers`
    /// (several may share one file's bytes, which count once).
    pub(super) fn new(buffers: &'b [Rc<Vec<u8>>], file_bytes: u64) -> Self {
        let mut seen = std::collections::HashSet::new();
        let buffer_bytes: u64 = buffers.iter().filter(|b| seen.insert(Rc::as_ptr(b))).map(|b| b.len() as u64).sum();
        AccessorLimits { buffers, file_bytes: file_bytes + buffer_bytes, decoded: 0 }
    }

    /// The buffers' data, for the crate's readers.
    pub(super) fn buffers(&self) -> &'b [Rc<Vec<u8>>] {
        self.buffers
    }

    /// Admits an accessor about to be read as `dimensions` of one of `types`: its shape must be
    /// one the readers handle, and its elements must be backed by bytes (module docs).
    pub(super) fn admit(
        &mut self,
        accessor: &Accessor,
        dimensions: Dimensions,
        types: &[DataType],
    ) -> Result<(), String> {
        let index = accessor.index();
        if accessor.dimensions() != dimensions || !types.contains(&accessor.data_type()) {
            return Err(format!(
                "accessor {index} has an unsupported type {:?} {:?}",
                accessor.dimensions(),
                accessor.data_type()
            ));
        }
        let stride_too_small =
            accessor.view().and_then(|view| view.stride()).is_some_and(|stride| stride < accessor.size());
        let sparse_empty = accessor.sparse().is_some_and(|sparse| sparse.count() == 0);
        if accessor.count() == 0 || sparse_empty || stride_too_small {
            return Err(format!("accessor {index} is empty or has a byte stride below its element size"));
        }
        let count = accessor.count() as u64;
        let element = accessor.size() as u64;
        let decoded = count.saturating_mul(element);
        match accessor.view() {
            Some(view) => {
                let stride = view.stride().unwrap_or(accessor.size()) as u64;
                let needed = extent(accessor.offset() as u64, stride, count, element);
                self.check_view(&view, needed, &format!("accessor {index}'s {count} elements"))?;
            }
            None if decoded > self.file_bytes => {
                return Err(format!(
                    "accessor {index} has no buffer view: its {count} zero-initialised elements ({}) are more data than the glTF and its buffers hold ({})",
                    describe_bytes(decoded),
                    describe_bytes(self.file_bytes)
                ));
            }
            None => {}
        }
        if let Some(sparse) = accessor.sparse() {
            let sparse_count = sparse.count() as u64;
            if sparse_count > count {
                return Err(format!("accessor {index} replaces {sparse_count} sparse elements but has only {count}"));
            }
            let indices = sparse.indices();
            let index_size = indices.index_type().size() as u64;
            let values = sparse.values();
            // The gltf crate steps through a sparse block by its view's stride and reads a whole
            // element at each step: a stride below the element (which glTF forbids on sparse
            // views anyway) would read past the step, and it panics.
            let stride_below = |view: &gltf::buffer::View, size: u64| view.stride().is_some_and(|s| (s as u64) < size);
            if stride_below(&indices.view(), index_size) || stride_below(&values.view(), element) {
                return Err(format!(
                    "accessor {index}'s sparse indices or values have a byte stride below their element size"
                ));
            }
            let index_stride = indices.view().stride().map_or(index_size, |s| s as u64);
            self.check_view(
                &indices.view(),
                extent(indices.offset() as u64, index_stride, sparse_count, index_size),
                &format!("accessor {index}'s {sparse_count} sparse indices"),
            )?;
            let value_stride = values.view().stride().map_or(element, |s| s as u64);
            self.check_view(
                &values.view(),
                extent(values.offset() as u64, value_stride, sparse_count, element),
                &format!("accessor {index}'s {sparse_count} sparse values"),
            )?;
        }
        self.decoded = self.decoded.saturating_add(decoded);
        if self.decoded > DECODE_FACTOR.saturating_mul(self.file_bytes) {
            return Err(format!(
                "reading accessor {index} brings the data decoded from this glTF to {}, more than {DECODE_FACTOR} times the {} of the glTF and its buffers (accessors reused by very many primitives?)",
                describe_bytes(self.decoded),
                describe_bytes(self.file_bytes)
            ));
        }
        Ok(())
    }

    /// `what` needs `needed` bytes of `view`, which must itself lie within its buffer's data.
    fn check_view(&self, view: &gltf::buffer::View, needed: u64, what: &str) -> Result<(), String> {
        let buffer = view.buffer().index();
        let available = self.buffers.get(buffer).map_or(0, |b| b.len() as u64);
        let end = (view.offset() as u64).saturating_add(view.length() as u64);
        if end > available {
            return Err(format!(
                "buffer view {} ends at byte {end} but buffer {buffer} holds {available} bytes",
                view.index()
            ));
        }
        if needed > view.length() as u64 {
            return Err(format!(
                "{what} need {} but buffer view {} holds {}",
                describe_bytes(needed),
                view.index(),
                describe_bytes(view.length() as u64)
            ));
        }
        Ok(())
    }
}

/// Bytes from the start of a view that `count` elements of `element` bytes, `stride` apart from
/// `offset`, reach (saturating: an absurd count just needs more than any view has).
fn extent(offset: u64, stride: u64, count: u64, element: u64) -> u64 {
    offset.saturating_add(stride.saturating_mul(count.saturating_sub(1))).saturating_add(element)
}

/// An accessor's elements as `N` floats each: floats as stored; integers, as glTF's
/// `KHR_mesh_quantization` allows them for positions, normals, tangents, texture coordinates and
/// morph targets, as the fractions glTF defines where the accessor is `normalized` (signed:
/// max(c / MAX, -1); unsigned: c / MAX), else as their values. None where the data lies outside
/// its buffer. Admit the accessor ([`AccessorLimits::admit`]) first.
pub(super) fn read_floats<const N: usize>(accessor: Accessor, buffers: &[Rc<Vec<u8>>]) -> Option<Vec<[f32; N]>>
where
    [f32; N]: Item,
    [i8; N]: Item,
    [u8; N]: Item,
    [i16; N]: Item,
    [u16; N]: Item,
    [u32; N]: Item,
{
    let normalized = accessor.normalized();
    let data = |buffer: gltf::Buffer| buffers.get(buffer.index()).map(|b| b.as_slice());
    fn convert<T: Copy, const N: usize>(iter: Iter<'_, [T; N]>, f: impl Fn(T) -> f32) -> Vec<[f32; N]>
    where
        [T; N]: Item,
    {
        iter.map(|element| element.map(&f)).collect()
    }
    let scale = |value: f32, max: f32, signed: bool| match (normalized, signed) {
        (true, true) => (value / max).max(-1.0),
        (true, false) => value / max,
        (false, _) => value,
    };
    Some(match accessor.data_type() {
        DataType::F32 => Iter::<[f32; N]>::new(accessor, data)?.collect(),
        DataType::I8 => convert(Iter::<[i8; N]>::new(accessor, data)?, |c| scale(c as f32, 127.0, true)),
        DataType::U8 => convert(Iter::<[u8; N]>::new(accessor, data)?, |c| scale(c as f32, 255.0, false)),
        DataType::I16 => convert(Iter::<[i16; N]>::new(accessor, data)?, |c| scale(c as f32, 32767.0, true)),
        DataType::U16 => convert(Iter::<[u16; N]>::new(accessor, data)?, |c| scale(c as f32, 65535.0, false)),
        DataType::U32 => convert(Iter::<[u32; N]>::new(accessor, data)?, |c| c as f32),
    })
}

/// Every component type a quantized attribute may have (`KHR_mesh_quantization`): the loader
/// admits each attribute with the subset glTF allows it.
pub(super) const QUANTIZED_TYPES: [DataType; 5] =
    [DataType::F32, DataType::I8, DataType::U8, DataType::I16, DataType::U16];
/// Normals and tangents: floats or normalized signed integers.
pub(super) const DIRECTION_TYPES: [DataType; 3] = [DataType::F32, DataType::I8, DataType::I16];
