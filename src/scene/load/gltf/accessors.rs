//! Vertex attributes read as floats whatever their stored type: floats, or
//! integers (`KHR_mesh_quantization`: positions, normals and texture
//! coordinates as 8- or 16-bit integers, normalized to [0, 1] or [−1, 1] or
//! taken as they are), dense or sparse (the gltf crate's reader lays a
//! sparse accessor's values over its base, or over zeros without one).

use gltf::accessor::{DataType, Item, Iter};

/// A stored component type and its value as a float.
trait Component: Item + Copy {
    /// The value, mapped to [0, 1] (unsigned) or [−1, 1] (signed) when the
    /// accessor is `normalized`.
    fn value(self, normalized: bool) -> f32;
}

impl Component for f32 {
    fn value(self, _: bool) -> f32 {
        self
    }
}

macro_rules! integer_component {
    ($($t:ty => $signed:expr),*) => {$(
        impl Component for $t {
            fn value(self, normalized: bool) -> f32 {
                let v = self as f32;
                match (normalized, $signed) {
                    (false, _) => v,
                    (true, false) => v / <$t>::MAX as f32,
                    (true, true) => (v / <$t>::MAX as f32).max(-1.0),
                }
            }
        }
    )*};
}

integer_component!(i8 => true, u8 => false, i16 => true, u16 => false, u32 => false);

/// The elements of `accessor`, of `N` components stored as `C`, as floats.
fn elements<'a, 's, C: Component, const N: usize>(
    accessor: &gltf::Accessor<'a>,
    data: impl Clone + Fn(gltf::Buffer<'a>) -> Option<&'s [u8]>,
) -> Option<Vec<[f32; N]>>
where
    [C; N]: Item,
{
    let normalized = accessor.normalized();
    Some(Iter::<[C; N]>::new(accessor.clone(), data)?.map(|e| e.map(|c| c.value(normalized))).collect())
}

/// The elements of `accessor` (each `N` components of any type) as floats,
/// from the buffers `data` gives; `None` when its data is out of reach.
pub(super) fn floats<'a, 's, const N: usize>(
    accessor: &gltf::Accessor<'a>,
    data: impl Clone + Fn(gltf::Buffer<'a>) -> Option<&'s [u8]>,
) -> Option<Vec<[f32; N]>>
where
    [f32; N]: Item,
    [i8; N]: Item,
    [u8; N]: Item,
    [i16; N]: Item,
    [u16; N]: Item,
    [u32; N]: Item,
{
    match accessor.data_type() {
        DataType::F32 => elements::<f32, N>(accessor, data),
        DataType::I8 => elements::<i8, N>(accessor, data),
        DataType::U8 => elements::<u8, N>(accessor, data),
        DataType::I16 => elements::<i16, N>(accessor, data),
        DataType::U16 => elements::<u16, N>(accessor, data),
        DataType::U32 => elements::<u32, N>(accessor, data),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normalized_integers_span_their_range_and_plain_ones_keep_their_value() {
        assert_eq!(255u8.value(true), 1.0);
        assert_eq!(65535u16.value(true), 1.0);
        assert_eq!(i8::MIN.value(true), -1.0);
        assert_eq!(i16::MIN.value(true), -1.0);
        assert_eq!((-64i16).value(false), -64.0);
        assert_eq!(300u16.value(false), 300.0);
        assert!((127i8.value(true) - 1.0).abs() < 1e-7);
    }
}
