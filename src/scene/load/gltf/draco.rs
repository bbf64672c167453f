//! `KHR_draco_mesh_compression`: a primitive whose geometry is one Draco
//! bitstream in a buffer view, decoded with `draco-core` (a pure-Rust
//! decoder of the Draco format, byte-compatible with Google's library) into
//! the attributes and triangles the accessors would otherwise hold. The
//! extension names, per attribute semantic, the Draco attribute's unique id;
//! the primitive's accessors then only say the count and type.
//!
//! The decode is bounded before it allocates: at most the scene's triangle
//! limit of faces, and the file limit's bytes of decoded values.

use draco_core::{DecodeLimits, DecoderBuffer, Mesh, MeshDecoder, PointIndex};
use gltf::json::Value;

use crate::limits::{Limit, Limits};

/// A primitive's decoded Draco geometry.
pub(super) struct DracoGeometry {
    mesh: Mesh,
    /// Semantic name (`POSITION`, `TEXCOORD_0`, …) → Draco attribute unique id.
    attributes: Vec<(String, u32)>,
}

impl DracoGeometry {
    /// `prim`'s Draco geometry, if it is compressed, decoded from `buffers`.
    ///
    /// # Errors
    ///
    /// A message when the extension's view is out of reach, the stream does
    /// not decode, or it decodes past the limits.
    pub(super) fn of(
        prim: &gltf::Primitive,
        doc: &gltf::Document,
        buffers: &[Vec<u8>],
        limits: &Limits,
    ) -> Result<Option<DracoGeometry>, String> {
        let Some(ext) = prim.extension_value("KHR_draco_mesh_compression") else { return Ok(None) };
        let view = ext
            .get("bufferView")
            .and_then(Value::as_u64)
            .and_then(|v| doc.views().nth(v as usize))
            .ok_or("its Draco extension names no buffer view of the file")?;
        let bytes = buffers
            .get(view.buffer().index())
            .and_then(|b| b.get(view.offset()..view.offset().checked_add(view.length())?))
            .ok_or("its Draco buffer view lies outside its buffer")?;
        let attributes = ext
            .get("attributes")
            .and_then(Value::as_object)
            .map(|a| a.iter().filter_map(|(k, v)| Some((k.clone(), u32::try_from(v.as_u64()?).ok()?))).collect())
            .unwrap_or_default();
        let mut bounds = DecodeLimits::default();
        bounds.max_faces = limits.get(Limit::Triangles);
        bounds.max_points = limits.get(Limit::Triangles).saturating_mul(3);
        bounds.max_decoded_bytes = limits.get(Limit::FileMb).saturating_mul(1 << 20);
        let mut buffer = DecoderBuffer::new(bytes).with_limits(bounds);
        let mut mesh = Mesh::new();
        MeshDecoder::new().decode(&mut buffer, &mut mesh).map_err(|e| format!("its Draco geometry: {e}"))?;
        Ok(Some(DracoGeometry { mesh, attributes }))
    }

    /// The values of attribute `semantic` (`N` components each, as floats;
    /// normalized integers mapped to [0, 1] or [−1, 1]), one per point, if
    /// the stream holds it.
    pub(super) fn floats<const N: usize>(&self, semantic: &str) -> Option<Vec<[f32; N]>> {
        let &(_, id) = self.attributes.iter().find(|(name, _)| name == semantic)?;
        let attribute = self.mesh.attribute_by_unique_id(id)?;
        let flat = attribute.read_f32s(self.mesh.num_points(), N);
        let scale = if attribute.normalized() { normalized_scale(attribute.data_type()) } else { 1.0 };
        Some(flat.chunks_exact(N).map(|c| std::array::from_fn(|k| c[k] * scale)).collect())
    }

    /// The triangles, as point indices.
    pub(super) fn indices(&self) -> Vec<u32> {
        self.mesh.faces().iter().flat_map(|f: &[PointIndex; 3]| f.map(|p| p.0)).collect()
    }
}

/// What a normalized integer of `t` is divided by.
fn normalized_scale(t: draco_core::DataType) -> f32 {
    use draco_core::DataType as D;
    match t {
        D::Int8 => 1.0 / 127.0,
        D::Uint8 => 1.0 / 255.0,
        D::Int16 => 1.0 / 32767.0,
        D::Uint16 => 1.0 / 65535.0,
        D::Int32 => 1.0 / 2_147_483_647.0,
        D::Uint32 => 1.0 / 4_294_967_295.0,
        _ => 1.0,
    }
}
