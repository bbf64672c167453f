//! `EXT_meshopt_compression` and `KHR_meshopt_compression`: buffer views
//! stored compressed by meshoptimizer (gltfpack's `-c`), decoded here with
//! the meshoptimizer library itself (the `meshopt` crate) into the place
//! the file reserves for them, usually a "fallback" buffer that holds no
//! bytes in the file; the accessors then read them as any others.
//!
//! A compressed view names its source (buffer, offset, length), its
//! element count and stride, a mode (`ATTRIBUTES`: vertex data; `TRIANGLES`:
//! an index buffer of triangles; `INDICES`: any index sequence) and a
//! filter applied after decoding (`OCTAHEDRAL` unit vectors, `QUATERNION`
//! rotations, `EXPONENTIAL` floats, and `COLOR` for the KHR extension).

use gltf::json::Value;

/// The two names of the extension (EXT, and KHR with its colour filter).
const NAMES: [&str; 2] = ["EXT_meshopt_compression", "KHR_meshopt_compression"];

/// Whether buffer `b` is a fallback: no bytes in the file, its views
/// decoded into it.
pub(super) fn is_fallback(b: &gltf::Buffer) -> bool {
    NAMES.iter().any(|n| b.extension_value(n).and_then(|e| e.get("fallback")).and_then(Value::as_bool) == Some(true))
}

/// Where a compressed view's bytes are and how they were compressed.
struct Compressed<'a> {
    source: (usize, usize, usize),
    count: usize,
    stride: usize,
    mode: &'a str,
    filter: &'a str,
}

impl<'a> Compressed<'a> {
    /// `view`'s compression, if it has one.
    fn of(view: &'a gltf::buffer::View) -> Result<Option<Compressed<'a>>, String> {
        let Some(e) = NAMES.iter().find_map(|n| view.extension_value(n)) else { return Ok(None) };
        let field = |k: &str| e.get(k).and_then(Value::as_u64).map(|v| v as usize);
        let number =
            |k: &str| field(k).ok_or_else(|| format!("buffer view {}: its meshopt {k} is missing", view.index()));
        let text = |k: &str| e.get(k).and_then(Value::as_str);
        Ok(Some(Compressed {
            source: (number("buffer")?, field("byteOffset").unwrap_or(0), number("byteLength")?),
            count: number("count")?,
            stride: number("byteStride")?,
            mode: text("mode").ok_or_else(|| format!("buffer view {}: its meshopt mode is missing", view.index()))?,
            filter: text("filter").unwrap_or("NONE"),
        }))
    }

    /// The decoded bytes: `count × stride`.
    fn decode(&self, source: &[u8]) -> Result<Vec<u8>, String> {
        let mut bytes = match (self.mode, self.stride) {
            ("ATTRIBUTES", s) if s % 4 == 0 && (4..=256).contains(&s) => vertices(source, self.count, s)?,
            ("TRIANGLES", 2) => indices::<u16>(::meshopt::decode_index_buffer(source, self.count))?,
            ("TRIANGLES", 4) => indices::<u32>(::meshopt::decode_index_buffer(source, self.count))?,
            ("INDICES", 2) => indices::<u16>(::meshopt::decode_index_sequence(source, self.count))?,
            ("INDICES", 4) => indices::<u32>(::meshopt::decode_index_sequence(source, self.count))?,
            (mode, stride) => return Err(format!("meshopt mode {mode} with a stride of {stride} bytes")),
        };
        filtered(&mut bytes, self.filter, self.stride)?;
        Ok(bytes)
    }
}

/// Decodes every compressed view of `doc` into its place in `buffers`.
///
/// # Errors
///
/// A message naming the view whose data is out of reach or does not decode.
pub(super) fn decode_views(doc: &gltf::Document, buffers: &mut [Vec<u8>]) -> Result<(), String> {
    for view in doc.views() {
        let Some(c) = Compressed::of(&view)? else { continue };
        let at = |what: &str| format!("buffer view {} ({what})", view.index());
        let (buffer, offset, length) = c.source;
        let source = buffers
            .get(buffer)
            .and_then(|b| b.get(offset..offset.checked_add(length)?))
            .ok_or_else(|| at("its compressed bytes lie outside their buffer"))?;
        // What is decoded fits the view, and the view its buffer (which is
        // within the file-size limit): checked before anything is allocated.
        let wanted = c.count.checked_mul(c.stride).filter(|&n| n <= view.length());
        let Some(wanted) = wanted else { return Err(at("it is smaller than its decoded elements")) };
        let target = view.buffer().index();
        let range = view.offset()..view.offset().checked_add(wanted).ok_or_else(|| at("it lies outside its buffer"))?;
        if buffers.get(target).is_none_or(|b| b.len() < range.end) {
            return Err(at("it lies outside its buffer"));
        }
        let bytes = c.decode(source).map_err(|e| at(&format!("meshopt: {e}")))?;
        if bytes.len() != wanted {
            return Err(at("meshopt: it decodes to another size"));
        }
        buffers[target][range].copy_from_slice(&bytes);
    }
    Ok(())
}

/// `count` vertices of `stride` bytes (a multiple of 4, at most 256).
fn vertices(source: &[u8], count: usize, stride: usize) -> Result<Vec<u8>, String> {
    /// One vertex's bytes (an array of any length has no `Default`).
    #[derive(Clone, Copy)]
    #[repr(transparent)]
    struct Vertex<const S: usize>([u8; S]);
    impl<const S: usize> Default for Vertex<S> {
        fn default() -> Self {
            Vertex([0; S])
        }
    }
    fn of<const S: usize>(source: &[u8], count: usize) -> Result<Vec<u8>, String> {
        let decoded = ::meshopt::decode_vertex_buffer::<Vertex<S>>(source, count).map_err(|e| e.to_string())?;
        Ok(decoded.iter().flat_map(|v| v.0).collect())
    }
    macro_rules! by_stride {
        ($($s:literal)*) => {
            match stride {
                $($s => of::<$s>(source, count),)*
                _ => Err(format!("a stride of {stride} bytes")),
            }
        };
    }
    by_stride!(4 8 12 16 20 24 28 32 36 40 44 48 52 56 60 64 68 72 76 80 84 88 92 96 100 104 108 112 116 120 124 128 132 136 140 144 148 152 156 160 164 168 172 176 180 184 188 192 196 200 204 208 212 216 220 224 228 232 236 240 244 248 252 256)
}

/// Decoded indices as little-endian bytes.
fn indices<T: Copy + Into<u32>>(decoded: ::meshopt::Result<Vec<T>>) -> Result<Vec<u8>, String> {
    let decoded = decoded.map_err(|e| e.to_string())?;
    let size = std::mem::size_of::<T>();
    Ok(decoded.iter().flat_map(|&i| i.into().to_le_bytes().into_iter().take(size)).collect())
}

/// Applies `filter` to decoded elements of `stride` bytes, in place.
fn filtered(bytes: &mut [u8], filter: &str, stride: usize) -> Result<(), String> {
    match (filter, stride) {
        ("NONE", _) => {}
        ("OCTAHEDRAL", 4) => in_bytes(bytes, |v: &mut Vec<[i8; 4]>| ::meshopt::decode_filter_oct(v)),
        ("OCTAHEDRAL", 8) => in_shorts(bytes, |v: &mut Vec<[i16; 4]>| ::meshopt::decode_filter_oct(v)),
        ("QUATERNION", 8) => in_shorts(bytes, |v: &mut Vec<[i16; 4]>| ::meshopt::decode_filter_quat(v)),
        ("COLOR", 4) => in_bytes(bytes, |v: &mut Vec<[u8; 4]>| ::meshopt::decode_filter_color(v)),
        ("COLOR", 8) => in_shorts(bytes, |v: &mut Vec<[u16; 4]>| ::meshopt::decode_filter_color(v)),
        // Each 32-bit value is decoded alone: the stride does not matter.
        ("EXPONENTIAL", s) if s % 4 == 0 => {
            let mut words: Vec<[u32; 1]> =
                bytes.chunks_exact(4).map(|w| [u32::from_le_bytes([w[0], w[1], w[2], w[3]])]).collect();
            ::meshopt::decode_filter_exp(&mut words);
            bytes.copy_from_slice(&words.iter().flat_map(|w| w[0].to_le_bytes()).collect::<Vec<_>>());
        }
        (filter, stride) => return Err(format!("meshopt filter {filter} with a stride of {stride} bytes")),
    }
    Ok(())
}

/// Runs `f` on `bytes` as four-byte elements, written back.
fn in_bytes<T: Copy + FromByte>(bytes: &mut [u8], f: impl Fn(&mut Vec<[T; 4]>)) {
    let mut v: Vec<[T; 4]> = bytes.chunks_exact(4).map(|c| [0, 1, 2, 3].map(|k| T::from_byte(c[k]))).collect();
    f(&mut v);
    bytes.copy_from_slice(&v.iter().flat_map(|e| e.map(FromByte::to_byte)).collect::<Vec<_>>());
}

/// Runs `f` on `bytes` as elements of four 16-bit values, written back.
fn in_shorts<T: Copy + FromShort>(bytes: &mut [u8], f: impl Fn(&mut Vec<[T; 4]>)) {
    let mut v: Vec<[T; 4]> =
        bytes.chunks_exact(8).map(|c| [0, 2, 4, 6].map(|k| T::from_short([c[k], c[k + 1]]))).collect();
    f(&mut v);
    bytes.copy_from_slice(&v.iter().flat_map(|e| e.iter().flat_map(|&x| x.to_short())).collect::<Vec<_>>());
}

/// An 8-bit component, signed or not.
trait FromByte: Sized {
    fn from_byte(b: u8) -> Self;
    fn to_byte(self) -> u8;
}

impl FromByte for i8 {
    fn from_byte(b: u8) -> i8 {
        i8::from_le_bytes([b])
    }
    fn to_byte(self) -> u8 {
        self.to_le_bytes()[0]
    }
}

impl FromByte for u8 {
    fn from_byte(b: u8) -> u8 {
        b
    }
    fn to_byte(self) -> u8 {
        self
    }
}

/// A 16-bit component, signed or not.
trait FromShort: Sized {
    fn from_short(b: [u8; 2]) -> Self;
    fn to_short(self) -> [u8; 2];
}

impl FromShort for i16 {
    fn from_short(b: [u8; 2]) -> i16 {
        i16::from_le_bytes(b)
    }
    fn to_short(self) -> [u8; 2] {
        self.to_le_bytes()
    }
}

impl FromShort for u16 {
    fn from_short(b: [u8; 2]) -> u16 {
        u16::from_le_bytes(b)
    }
    fn to_short(self) -> [u8; 2] {
        self.to_le_bytes()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn decoded(mode: &str, filter: &str, stride: usize, count: usize, source: &[u8]) -> Vec<u8> {
        let c = Compressed { source: (0, 0, source.len()), count, stride, mode, filter };
        c.decode(source).unwrap()
    }

    /// What meshoptimizer's encoders write, the decoders give back: an
    /// index sequence, and floats through the exponential filter (to the
    /// filter's precision) in vertices of 12 bytes.
    #[test]
    fn encoded_streams_decode_to_what_was_encoded() {
        let indices: Vec<u32> = vec![0, 1, 2, 2, 1, 3, 7, 5, 4];
        let encoded = ::meshopt::encode_index_sequence(&indices, 8).unwrap();
        let bytes = decoded("INDICES", "NONE", 4, indices.len(), &encoded);
        let back: Vec<u32> = bytes.chunks_exact(4).map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]])).collect();
        assert_eq!(back, indices);

        let floats: Vec<[f32; 3]> =
            (0..50).map(|i| [i as f32 * 0.37 - 4.0, (i as f32).sin() * 100.0, 1e-3 * i as f32]).collect();
        let words = ::meshopt::encode_filter_exp(&floats, 16, ::meshopt::EncodeExpMode::Separate);
        let encoded = ::meshopt::encode_vertex_buffer(&words).unwrap();
        let bytes = decoded("ATTRIBUTES", "EXPONENTIAL", 12, floats.len(), &encoded);
        let back: Vec<f32> = bytes.chunks_exact(4).map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]])).collect();
        for (got, want) in back.iter().zip(floats.iter().flatten()) {
            assert!((got - want).abs() <= want.abs() * 1e-3 + 1e-6, "{got} vs {want}");
        }
    }

    /// A stride or filter the format does not have is an error, not a panic.
    #[test]
    fn an_unknown_mode_or_filter_is_an_error() {
        let c = Compressed { source: (0, 0, 0), count: 1, stride: 6, mode: "ATTRIBUTES", filter: "NONE" };
        assert!(c.decode(&[]).is_err());
        let c = Compressed { stride: 4, filter: "SPIRAL", ..c };
        assert!(c.decode(&[0xa0; 32]).is_err());
    }
}
