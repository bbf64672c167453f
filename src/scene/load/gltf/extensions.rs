//! The glTF extensions kage knows, in one table: what it does with each, and
//! what a file that uses or requires one is told.
//!
//! A file lists the extensions it uses (`extensionsUsed`) and those a reader
//! must understand to draw it right (`extensionsRequired`). An extension
//! kage reads needs no word; one it draws without (a clear coat, sheen) is a
//! warning naming it; one it cannot decode (KTX2, WebP, AVIF and DDS
//! images) refuses a file that requires it, with what to do instead, and is
//! passed over where the file only uses it (its uncompressed data or its
//! fallback image is then what is drawn). An extension kage does not know is
//! an error where it is required and a warning where it is only used.

/// What kage does with an extension.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Support {
    /// Read and drawn.
    Read,
    /// Drawn without what the extension adds (the text says what is lost).
    Without(&'static str),
    /// Cannot be decoded (the text says what to do instead).
    Refused(&'static str),
}

/// Every extension kage knows.
const EXTENSIONS: &[(&str, Support)] = &[
    ("KHR_lights_punctual", Support::Read),
    ("KHR_materials_transmission", Support::Read),
    ("KHR_materials_ior", Support::Read),
    ("KHR_materials_emissive_strength", Support::Read),
    ("KHR_materials_unlit", Support::Read),
    ("KHR_texture_transform", Support::Read),
    ("KHR_mesh_quantization", Support::Read),
    (
        "KHR_materials_clearcoat",
        Support::Without("the clear coat is approximated: its factor mirrors 4% of the environment, sharply"),
    ),
    (
        "KHR_materials_sheen",
        Support::Without(
            "the sheen is approximated: a diffuse tint of its colour factor (a quarter of it), its textures not read",
        ),
    ),
    (
        "KHR_materials_specular",
        Support::Without("its strength and colour factors set the highlight's reflectance; its textures are not read"),
    ),
    ("KHR_materials_volume", Support::Without("the volume's thickness and attenuation are not drawn")),
    ("KHR_materials_iridescence", Support::Without("the iridescence is not drawn")),
    ("KHR_materials_anisotropy", Support::Without("highlights are drawn round, not stretched")),
    ("KHR_materials_dispersion", Support::Without("the dispersion is not drawn")),
    ("KHR_materials_variants", Support::Without("each primitive's default material is drawn")),
    ("KHR_materials_pbrSpecularGlossiness", Support::Without("its metallic-roughness fallback is drawn")),
    ("KHR_animation_pointer", Support::Without("animations are not played")),
    ("KHR_xmp", Support::Without("the metadata is not read")),
    ("KHR_xmp_json_ld", Support::Without("the metadata is not read")),
    ("KHR_draco_mesh_compression", Support::Read),
    ("EXT_meshopt_compression", Support::Read),
    ("KHR_meshopt_compression", Support::Read),
    ("KHR_texture_basisu", Support::Refused("convert its KTX2 images to PNG or JPEG")),
    ("EXT_texture_webp", Support::Refused("convert its WebP images to PNG or JPEG")),
    ("EXT_texture_avif", Support::Refused("convert its AVIF images to PNG or JPEG")),
    ("MSFT_texture_dds", Support::Refused("convert its DDS images to PNG or JPEG")),
];

fn support(name: &str) -> Option<Support> {
    EXTENSIONS.iter().find(|(n, _)| *n == name).map(|&(_, s)| s)
}

/// Checks the extensions `root` uses and requires: an error for a required
/// one kage cannot decode or does not know; a warning in `warnings` for one
/// drawn without what it adds, and for an unknown one only used. The
/// required list is emptied once checked (the gltf crate would refuse the
/// ones kage reads itself, such as `KHR_mesh_quantization`).
///
/// # Errors
///
/// The first required extension kage cannot honour, named.
pub(super) fn check(root: &mut gltf::json::Root, warnings: &mut Vec<String>) -> Result<(), String> {
    let required = std::mem::take(&mut root.extensions_required);
    for name in &required {
        match support(name) {
            Some(Support::Read | Support::Without(_)) => {}
            Some(Support::Refused(instead)) => {
                return Err(format!(
                    "the file requires the glTF extension {name}, which kage cannot decode: {instead}"
                ));
            }
            None => return Err(format!("the file requires the glTF extension {name}, which kage does not know")),
        }
    }
    for name in root.extensions_used.iter().chain(required.iter().filter(|r| !root.extensions_used.contains(r))) {
        match support(name) {
            Some(Support::Without(lost)) => warnings.push(format!("the file uses {name}: {lost}")),
            None => {
                warnings.push(format!("the file uses the glTF extension {name}, which kage does not know; ignored"))
            }
            Some(Support::Read | Support::Refused(_)) => {}
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn root(required: &[&str], used: &[&str]) -> gltf::json::Root {
        gltf::json::Root {
            extensions_required: required.iter().map(|s| (*s).to_string()).collect(),
            extensions_used: used.iter().map(|s| (*s).to_string()).collect(),
            ..Default::default()
        }
    }

    #[test]
    fn a_required_extension_kage_cannot_decode_is_named_with_what_to_do() {
        let mut warnings = Vec::new();
        let e = check(&mut root(&["KHR_texture_basisu"], &[]), &mut warnings).unwrap_err();
        assert!(e.contains("KHR_texture_basisu") && e.contains("PNG or JPEG"), "{e}");
        let e = check(&mut root(&["EXT_frobnicate"], &[]), &mut warnings).unwrap_err();
        assert!(e.contains("EXT_frobnicate") && e.contains("does not know"), "{e}");
    }

    #[test]
    fn extensions_read_pass_and_the_rest_are_warned_by_name() {
        let mut warnings = Vec::new();
        let mut r =
            root(&["KHR_mesh_quantization"], &["KHR_mesh_quantization", "KHR_materials_sheen", "EXT_frobnicate"]);
        check(&mut r, &mut warnings).unwrap();
        assert!(r.extensions_required.is_empty());
        assert_eq!(warnings.len(), 2, "{warnings:?}");
        assert!(warnings[0].contains("KHR_materials_sheen") && warnings[0].contains("approximated"));
        assert!(warnings[1].contains("EXT_frobnicate") && warnings[1].contains("ignored"));
        // Compression only used: the file's uncompressed data is drawn, no word.
        warnings.clear();
        check(&mut root(&[], &["KHR_draco_mesh_compression"]), &mut warnings).unwrap();
        assert!(warnings.is_empty());
    }
}
