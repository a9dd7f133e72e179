//! Buffers, buffer views and accessors: the bytes of each buffer (GLB chunk, data URI or
//! file) and bounds-checked readers of accessor elements.

use gltf::accessor::{DataType, Dimensions};

use super::uri::UriLimit;
use super::Loader;
use crate::error::RenderError;

/// Largest element count of an accessor without a buffer view (all zeros).
const MAX_VIEWLESS_COUNT: usize = 1 << 24;

/// A bounds-checked view of an accessor's bytes.
pub(super) struct AccessorData<'b> {
    pub(super) bytes: &'b [u8],
    /// Byte offset of element 0 in `bytes`.
    pub(super) offset: usize,
    pub(super) stride: usize,
    pub(super) count: usize,
    pub(super) data_type: DataType,
    pub(super) normalized: bool,
}

impl AccessorData<'_> {
    /// Component `c` of element `i` as f32 (normalised integers mapped to [0, 1] / [-1, 1]).
    pub(super) fn get(&self, i: usize, c: usize) -> f32 {
        let size = self.data_type.size();
        let at = self.offset + i * self.stride + c * size;
        let b = &self.bytes[at..at + size];
        let n = self.normalized;
        match self.data_type {
            DataType::F32 => f32::from_le_bytes([b[0], b[1], b[2], b[3]]),
            DataType::U8 if n => f32::from(b[0]) / 255.0,
            DataType::U8 => f32::from(b[0]),
            DataType::I8 if n => (f32::from(b[0] as i8) / 127.0).max(-1.0),
            DataType::I8 => f32::from(b[0] as i8),
            DataType::U16 => {
                let v = f32::from(u16::from_le_bytes([b[0], b[1]]));
                if n {
                    v / 65535.0
                } else {
                    v
                }
            }
            DataType::I16 => {
                let v = f32::from(i16::from_le_bytes([b[0], b[1]]));
                if n {
                    (v / 32767.0).max(-1.0)
                } else {
                    v
                }
            }
            DataType::U32 => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f32,
        }
    }

    /// Element `i` as an unsigned integer (index buffers).
    pub(super) fn get_u32(&self, i: usize) -> u32 {
        let size = self.data_type.size();
        let at = self.offset + i * self.stride;
        let b = &self.bytes[at..at + size];
        match self.data_type {
            DataType::U8 => u32::from(b[0]),
            DataType::U16 => u32::from(u16::from_le_bytes([b[0], b[1]])),
            _ => u32::from_le_bytes([b[0], b[1], b[2], b[3]]),
        }
    }
}

impl Loader<'_> {
    /// The data of every buffer: the GLB binary chunk or the bytes of its URI, at least
    /// `byteLength` long.
    pub(super) fn load_buffers(
        &self,
        doc: &gltf::Document,
        mut bin: Option<&[u8]>,
    ) -> Result<Vec<Vec<u8>>, RenderError> {
        let mut out = Vec::new();
        for buffer in doc.buffers() {
            let what = format!("buffers[{}]", buffer.index());
            let data = match buffer.source() {
                gltf::buffer::Source::Bin => bin
                    .take()
                    .ok_or_else(|| {
                        self.err(format!(
                            "{what} refers to the GLB binary chunk, which is missing"
                        ))
                    })?
                    .to_vec(),
                gltf::buffer::Source::Uri(uri) => {
                    self.read_uri(uri, &what, UriLimit::UpTo(buffer.length() as u64))?
                }
            };
            if data.len() < buffer.length() {
                return Err(self.err(format!(
                    "{what}.byteLength is {} but the data has only {} bytes",
                    buffer.length(),
                    data.len()
                )));
            }
            out.push(data);
        }
        Ok(out)
    }

    /// The bytes of buffer view `view`, bounds-checked.
    pub(super) fn view_bytes<'b>(
        &self,
        view: &gltf::buffer::View<'_>,
        buffers: &'b [Vec<u8>],
    ) -> Result<&'b [u8], RenderError> {
        let data = buffers.get(view.buffer().index()).ok_or_else(|| {
            self.err(format!("bufferViews[{}].buffer out of range", view.index()))
        })?;
        let start = view.offset();
        start
            .checked_add(view.length())
            .and_then(|end| data.get(start..end))
            .ok_or_else(|| {
                self.err(format!(
                    "bufferViews[{}]: bytes {}..{}+{} exceed buffers[{}] ({} bytes)",
                    view.index(),
                    start,
                    start,
                    view.length(),
                    view.buffer().index(),
                    data.len()
                ))
            })
    }

    /// A bounds-checked reader for accessor `acc`; `allowed` lists acceptable dimensions.
    pub(super) fn accessor<'b>(
        &mut self,
        acc: &gltf::Accessor<'_>,
        buffers: &'b [Vec<u8>],
        allowed: &[Dimensions],
        what: &str,
    ) -> Result<AccessorData<'b>, RenderError> {
        let i = acc.index();
        if !allowed.contains(&acc.dimensions()) {
            return Err(self.err(format!(
                "accessors[{i}] ({what}) has type {:?}, expected one of {allowed:?}",
                acc.dimensions()
            )));
        }
        if acc.sparse().is_some() {
            return Err(self.err(format!(
                "accessors[{i}] ({what}) is sparse, which is not supported"
            )));
        }
        let elem = acc.data_type().size() * acc.dimensions().multiplicity();
        let count = acc.count();
        let Some(view) = acc.view() else {
            // No buffer view: all zeros (glTF 2.0, 3.6.2.3). Bound the count, since no data
            // bounds it.
            if count > MAX_VIEWLESS_COUNT {
                return Err(self.err(format!(
                    "accessors[{i}] ({what}).count {count} exceeds {MAX_VIEWLESS_COUNT} for an accessor without bufferView"
                )));
            }
            static ZEROS: [u8; 16] = [0; 16];
            return Ok(AccessorData {
                bytes: &ZEROS,
                offset: 0,
                stride: 0,
                count,
                data_type: acc.data_type(),
                normalized: acc.normalized(),
            });
        };
        let bytes = self.view_bytes(&view, buffers)?;
        let stride = view.stride().unwrap_or(elem);
        if stride < elem {
            return Err(self.err(format!(
                "bufferViews[{}].byteStride {stride} is smaller than the {elem}-byte elements of accessors[{i}]",
                view.index()
            )));
        }
        let offset = acc.offset();
        let needed = if count == 0 {
            Some(0)
        } else {
            (count - 1)
                .checked_mul(stride)
                .and_then(|v| v.checked_add(elem))
                .and_then(|v| v.checked_add(offset))
        };
        match needed {
            Some(n) if n <= bytes.len() => {}
            _ => {
                return Err(self.err(format!(
                    "accessors[{i}] ({what}): {count} elements of {elem} bytes at byteOffset {offset} with stride {stride} exceed bufferViews[{}] ({} bytes)",
                    view.index(),
                    bytes.len()
                )))
            }
        }
        Ok(AccessorData {
            bytes,
            offset,
            stride,
            count,
            data_type: acc.data_type(),
            normalized: acc.normalized(),
        })
    }
}
