//! Accessors read with every offset, stride and count checked against the buffers (glTF 2.0 spec, section 3.6
//! "Binary Data Storage"): a bad accessor is an error, never a panic or a read out of bounds.

use ::gltf::json::accessor::{ComponentType, Type};
use ::gltf::json::validation::Checked;

use super::{Doc, GltfError, MAX_VIEWLESS_ELEMENTS};

/// Bytes per component.
fn component_size(ct: ComponentType) -> usize {
    match ct {
        ComponentType::I8 | ComponentType::U8 => 1,
        ComponentType::I16 | ComponentType::U16 => 2,
        ComponentType::U32 | ComponentType::F32 => 4,
    }
}

fn component_count(ty: Type) -> usize {
    match ty {
        Type::Scalar => 1,
        Type::Vec2 => 2,
        Type::Vec3 => 3,
        Type::Vec4 | Type::Mat2 => 4,
        Type::Mat3 => 9,
        Type::Mat4 => 16,
    }
}

/// One component as f32; normalised integers map to [0, 1] or [-1, 1] (glTF 2.0 spec, section 3.11
/// "Animations", normalisation equations). `bytes` holds at least `component_size(ct)` bytes.
fn component_f32(ct: ComponentType, bytes: &[u8], normalized: bool) -> f32 {
    let b = |i: usize| bytes[i];
    match ct {
        ComponentType::F32 => f32::from_le_bytes([b(0), b(1), b(2), b(3)]),
        ComponentType::U8 if normalized => b(0) as f32 / 255.0,
        ComponentType::U8 => b(0) as f32,
        ComponentType::I8 if normalized => (b(0) as i8 as f32 / 127.0).max(-1.0),
        ComponentType::I8 => b(0) as i8 as f32,
        ComponentType::U16 if normalized => u16::from_le_bytes([b(0), b(1)]) as f32 / 65535.0,
        ComponentType::U16 => u16::from_le_bytes([b(0), b(1)]) as f32,
        ComponentType::I16 if normalized => (i16::from_le_bytes([b(0), b(1)]) as f32 / 32767.0).max(-1.0),
        ComponentType::I16 => i16::from_le_bytes([b(0), b(1)]) as f32,
        ComponentType::U32 => u32::from_le_bytes([b(0), b(1), b(2), b(3)]) as f32,
    }
}

/// One unsigned integer component (indices); `None` for signed or float types.
fn component_u32(ct: ComponentType, bytes: &[u8]) -> Option<u32> {
    match ct {
        ComponentType::U8 => Some(bytes[0] as u32),
        ComponentType::U16 => Some(u16::from_le_bytes([bytes[0], bytes[1]]) as u32),
        ComponentType::U32 => Some(u32::from_le_bytes([bytes[0], bytes[1], bytes[2], bytes[3]])),
        _ => None,
    }
}

/// Reads accessor `index` as `N`-component float vectors. `usage` (e.g. "POSITION") is for messages.
pub(super) fn read_vectors<const N: usize>(doc: &Doc, index: usize, usage: &str) -> Result<Vec<[f32; N]>, GltfError> {
    let flat = read_flat(doc, index, N, usage, |ct, bytes, normalized| Some(component_f32(ct, bytes, normalized)))?;
    Ok(flat.chunks_exact(N).map(|c| std::array::from_fn(|i| c[i])).collect())
}

/// Reads an index accessor (SCALAR of unsigned byte, short or int).
pub(super) fn read_indices(doc: &Doc, index: usize) -> Result<Vec<u32>, GltfError> {
    read_flat(doc, index, 1, "indices", |ct, bytes, _| component_u32(ct, bytes))
}

/// Reads all components of accessor `index` (which must have `dims` components per element) into one flat
/// vector, applying sparse substitution. `decode` returns `None` for component types the usage does not allow.
fn read_flat<T: Copy + Default>(
    doc: &Doc,
    index: usize,
    dims: usize,
    usage: &str,
    decode: impl Fn(ComponentType, &[u8], bool) -> Option<T>,
) -> Result<Vec<T>, GltfError> {
    let pointer = format!("/accessors/{index}");
    let accessor = doc.root.accessors.get(index).ok_or_else(|| {
        doc.invalid(&pointer, format!("{usage} refers to a missing accessor ({} defined)", doc.root.accessors.len()))
    })?;
    let ct = match &accessor.component_type {
        Checked::Valid(g) => g.0,
        Checked::Invalid => return Err(doc.invalid(&pointer, "invalid componentType")),
    };
    let Checked::Valid(ty) = accessor.type_ else {
        return Err(doc.invalid(&pointer, "invalid type"));
    };
    if component_count(ty) != dims {
        return Err(doc.invalid(&pointer, format!("type {ty:?} for {usage}, which needs {dims} component(s)")));
    }
    let csize = component_size(ct);
    if decode(ct, &[0; 4], accessor.normalized).is_none() {
        return Err(doc.invalid(&pointer, format!("componentType {ct:?} is not allowed for {usage}")));
    }
    let elem_size = csize * dims;
    let count = accessor.count.0;
    let mut out = match accessor.buffer_view {
        Some(view) => {
            let offset = accessor.byte_offset.map_or(0, |o| o.0);
            let elements = strided_elements(doc, view.value(), offset, count, elem_size, true, &pointer)?;
            let mut out = Vec::with_capacity(elements.count * dims);
            for element in elements.iter() {
                for c in element.chunks_exact(csize) {
                    out.push(decode(ct, c, accessor.normalized).unwrap_or_default());
                }
            }
            out
        }
        None if count > MAX_VIEWLESS_ELEMENTS => {
            return Err(GltfError::TooLarge {
                what: doc.what.into(),
                msg: format!("{pointer}: {count} elements without a bufferView (at most {MAX_VIEWLESS_ELEMENTS})"),
            });
        }
        // Without a buffer view the values are zeros (then sparse substitution); glTF spec section 3.6.2.
        None => vec![T::default(); count as usize * dims],
    };
    if let Some(sparse) = &accessor.sparse {
        let sparse_pointer = format!("{pointer}/sparse");
        let n = sparse.count.0;
        if n > count {
            return Err(doc.invalid(&sparse_pointer, format!("{n} sparse values for {count} elements")));
        }
        let ict = match &sparse.indices.component_type {
            Checked::Valid(g) => g.0,
            Checked::Invalid => return Err(doc.invalid(&sparse_pointer, "invalid indices componentType")),
        };
        let targets = strided_elements(
            doc,
            sparse.indices.buffer_view.value(),
            sparse.indices.byte_offset.0,
            n,
            component_size(ict),
            false,
            &format!("{sparse_pointer}/indices"),
        )?;
        let values = strided_elements(
            doc,
            sparse.values.buffer_view.value(),
            sparse.values.byte_offset.0,
            n,
            elem_size,
            false,
            &format!("{sparse_pointer}/values"),
        )?;
        for (target, value) in targets.iter().zip(values.iter()) {
            let target = component_u32(ict, target)
                .filter(|&t| (t as u64) < count)
                .ok_or_else(|| doc.out_of_bounds(&sparse_pointer, format!("a sparse index is not below {count}")))?;
            for (k, c) in value.chunks_exact(csize).enumerate() {
                out[target as usize * dims + k] = decode(ct, c, accessor.normalized).unwrap_or_default();
            }
        }
    }
    Ok(out)
}

/// `count` elements of `elem_size` bytes, `stride` bytes apart, all inside `data` (checked on construction).
struct Strided<'d> {
    data: &'d [u8],
    stride: usize,
    elem_size: usize,
    count: usize,
}

impl<'d> Strided<'d> {
    fn iter(&self) -> impl Iterator<Item = &'d [u8]> + use<'d> {
        let (data, stride, elem_size) = (self.data, self.stride, self.elem_size);
        (0..self.count).map(move |i| &data[i * stride..i * stride + elem_size])
    }
}

/// The `count` elements of `elem_size` bytes starting `offset` bytes into buffer view `view`, honouring its
/// byteStride when `strided` (sparse index and value views are tightly packed).
fn strided_elements<'d>(
    doc: &'d Doc,
    view: usize,
    offset: u64,
    count: u64,
    elem_size: usize,
    strided: bool,
    pointer: &str,
) -> Result<Strided<'d>, GltfError> {
    let (data, stride) = view_bytes(doc, view)?;
    let stride = match stride.filter(|_| strided) {
        Some(s) if s < elem_size => {
            return Err(doc.invalid(
                format!("/bufferViews/{view}"),
                format!("byteStride {s} is smaller than the {elem_size}-byte elements of {pointer}"),
            ));
        }
        Some(s) => s,
        None => elem_size,
    };
    if count == 0 {
        return Ok(Strided { data, stride, elem_size, count: 0 });
    }
    // offset + stride * (count - 1) + elem_size, in u64 so that no count can overflow.
    let needed = (stride as u64)
        .checked_mul(count - 1)
        .and_then(|v| v.checked_add(offset))
        .and_then(|v| v.checked_add(elem_size as u64));
    let Some(needed) = needed.filter(|&n| n <= data.len() as u64) else {
        return Err(doc.out_of_bounds(
            pointer,
            format!(
                "{count} elements of {elem_size} bytes every {stride} bytes from byte {offset} do not fit in \
                 bufferView {view} ({} bytes)",
                data.len()
            ),
        ));
    };
    Ok(Strided { data: &data[offset as usize..needed as usize], stride, elem_size, count: count as usize })
}

/// The bytes of buffer view `index` and its byteStride, checked against its buffer.
pub(super) fn view_bytes<'d>(doc: &'d Doc, index: usize) -> Result<(&'d [u8], Option<usize>), GltfError> {
    let pointer = format!("/bufferViews/{index}");
    let view = doc.root.buffer_views.get(index).ok_or_else(|| {
        doc.invalid(&pointer, format!("missing buffer view ({} defined)", doc.root.buffer_views.len()))
    })?;
    let buffer_index = view.buffer.value();
    let buffer = doc
        .buffers
        .get(buffer_index)
        .ok_or_else(|| doc.invalid(&pointer, format!("refers to missing buffer {buffer_index}")))?;
    let start = view.byte_offset.map_or(0, |o| o.0);
    let end = start.checked_add(view.byte_length.0).filter(|&end| end <= buffer.len() as u64).ok_or_else(|| {
        doc.out_of_bounds(
            &pointer,
            format!(
                "bytes {start}..{start}+{} lie outside buffer {buffer_index} ({} bytes)",
                view.byte_length.0,
                buffer.len()
            ),
        )
    })?;
    Ok((&buffer[start as usize..end as usize], view.byte_stride.map(|s| s.0)))
}
