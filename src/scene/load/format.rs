//! The kinds of input file kage reads, in one table: which extensions name
//! each, what it is called in messages, and which files beside it it may read
//! (a viewer watches those for changes). The loaders, the command line, the
//! viewer and batch jobs all ask this table, so a format added here is known
//! everywhere at once.

use std::path::Path;

/// A kind of input file.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum InputFormat {
    /// A kage scene file (TOML).
    Scene,
    /// Wavefront OBJ, with its MTL materials.
    Obj,
    /// STL, binary or ASCII.
    Stl,
    /// OFF (Object File Format), as OpenSCAD writes it.
    Off,
    /// glTF 2.0, text or binary.
    Gltf,
    /// OpenSCAD's flattened CSG tree (`openscad -o x.csg`).
    Csg,
    /// OpenSCAD source: the `openscad` program turns it into a `.csg` first
    /// (the library reads only the `.csg`).
    Scad,
}

/// One row of the table.
struct Row {
    format: InputFormat,
    extensions: &'static [&'static str],
    /// Extensions of files beside it that it may read.
    companions: &'static [&'static str],
}

/// Texture files a model or scene may name.
const TEXTURES: &[&str] = &["png", "jpg", "jpeg", "exr"];

/// Every format, in the order messages list them.
const TABLE: [Row; 7] = [
    Row { format: InputFormat::Scene, extensions: &["toml"], companions: &[] },
    Row { format: InputFormat::Obj, extensions: &["obj"], companions: &["mtl"] },
    Row { format: InputFormat::Stl, extensions: &["stl"], companions: &[] },
    Row { format: InputFormat::Off, extensions: &["off"], companions: &[] },
    Row { format: InputFormat::Gltf, extensions: &["gltf", "glb"], companions: &["bin"] },
    Row { format: InputFormat::Csg, extensions: &["csg"], companions: &["stl", "obj", "off", "svg", "dxf", "dat"] },
    Row { format: InputFormat::Scad, extensions: &["scad"], companions: &["stl", "obj", "off", "svg", "dxf", "dat"] },
];

impl InputFormat {
    /// Every format, in the table's order.
    pub const ALL: [InputFormat; TABLE.len()] = {
        let mut all = [InputFormat::Scene; TABLE.len()];
        let mut i = 0;
        while i < TABLE.len() {
            all[i] = TABLE[i].format;
            i += 1;
        }
        all
    };

    /// The format a file's extension (in any letter case) names, if any.
    #[must_use]
    pub fn from_path(path: &Path) -> Option<InputFormat> {
        let ext = path.extension()?.to_str()?.to_ascii_lowercase();
        TABLE.iter().find(|row| row.extensions.contains(&ext.as_str())).map(|row| row.format)
    }

    fn row(self) -> &'static Row {
        TABLE.iter().find(|row| row.format == self).expect("every format has a row")
    }

    /// The extensions that name the format, lower case, without the dot.
    #[must_use]
    pub fn extensions(self) -> &'static [&'static str] {
        self.row().extensions
    }

    /// Whether it is a model (drawn with kage's default lights, camera and
    /// ground) rather than a scene file.
    #[must_use]
    pub fn is_model(self) -> bool {
        self != InputFormat::Scene
    }

    /// The extensions of every file that, changed, changes what a file of
    /// one of the formats shows (the files themselves, what they name beside
    /// them, textures), without repeats.
    #[must_use]
    pub fn watched_extensions() -> Vec<&'static str> {
        let mut out: Vec<&'static str> = Vec::new();
        for ext in TABLE.iter().flat_map(|row| row.extensions.iter().chain(row.companions)).chain(TEXTURES) {
            if !out.contains(ext) {
                out.push(ext);
            }
        }
        out
    }

    /// What kage reads, for messages: "scene files (.toml), models (.obj,
    /// …) and OpenSCAD files (.scad)".
    #[must_use]
    pub fn described() -> String {
        let dotted = |f: InputFormat| f.extensions().iter().map(|e| format!(".{e}")).collect::<Vec<_>>();
        let models: Vec<String> =
            Self::ALL.into_iter().filter(|&f| f.is_model() && f != InputFormat::Scad).flat_map(dotted).collect();
        format!(
            "scene files ({}), models ({}) and OpenSCAD files ({})",
            dotted(InputFormat::Scene).join(", "),
            models.join(", "),
            dotted(InputFormat::Scad).join(", ")
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_format_has_one_row_and_is_found_by_each_of_its_extensions() {
        for format in InputFormat::ALL {
            assert_eq!(TABLE.iter().filter(|r| r.format == format).count(), 1, "{format:?}");
            for ext in format.extensions() {
                assert_eq!(InputFormat::from_path(Path::new(&format!("a/b.{}", ext.to_uppercase()))), Some(format));
            }
        }
        assert_eq!(InputFormat::from_path(Path::new("model.ply")), None);
        assert_eq!(InputFormat::from_path(Path::new("noextension")), None);
        let said = InputFormat::described();
        assert!(said.contains(".off") && said.contains(".glb") && said.contains("(.scad)"), "{said}");
        assert!(InputFormat::watched_extensions().contains(&"mtl"));
    }
}
