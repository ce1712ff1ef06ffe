//! What a file is, told by its name and its first bytes before any parser
//! sees it: a scene file (`.toml`), a mesh strata reads, or a format it
//! does not read, named. A file whose first bytes contradict its name (a
//! binary glTF named `.obj`, an FBX file named `.toml`) is refused saying
//! what it holds, instead of a parser's confusion (`line 1: key with no
//! value`, `stream did not contain valid UTF-8`).

use crate::error::{InputError, InputResult};
use std::fmt;
use std::io::Read;
use std::path::Path;

/// How many bytes of a file are read to tell what it is.
pub(crate) const HEAD_BYTES: u64 = 4096;

/// The formats a file can be told to be: those strata reads, then those
/// it only names.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Format {
    Scene,
    Obj,
    Gltf,
    Glb,
    Ply,
    Off,
    Stl,
    Fbx,
    Collada,
    Blender,
    Usd,
    Zip,
    Image(&'static str),
}

impl Format {
    /// The mesh format of a (lower-case) extension that strata reads.
    pub(crate) fn of_mesh_extension(extension: &str) -> Option<Format> {
        Some(match extension {
            "obj" => Format::Obj,
            "gltf" => Format::Gltf,
            "glb" => Format::Glb,
            "ply" => Format::Ply,
            "off" => Format::Off,
            "stl" => Format::Stl,
            _ => return None,
        })
    }

    /// The extension strata reads this format by, if it reads it.
    fn extension(self) -> Option<&'static str> {
        Some(match self {
            Format::Scene => "toml",
            Format::Obj => "obj",
            Format::Gltf => "gltf",
            Format::Glb => "glb",
            Format::Ply => "ply",
            Format::Off => "off",
            Format::Stl => "stl",
            _ => return None,
        })
    }

    /// Whether a file named for `self` may hold `found` and still read:
    /// the glTF loader reads JSON and binary glTF under either name.
    fn agrees_with(self, found: Format) -> bool {
        self == found || matches!((self, found), (Format::Gltf, Format::Glb))
    }

    /// What to do with a file of this format that was named for another.
    fn advice(self) -> String {
        match (self, self.extension()) {
            (Format::Scene, _) => "a scene file is read as one when it is named .toml".into(),
            (_, Some(extension)) => format!("name it .{extension} to read it as one"),
            (Format::Image(_), None) => {
                "an image is a texture that a mesh's material names, or an \
                 environment light's map"
                    .into()
            }
            (_, None) => convert_advice(),
        }
    }
}

impl fmt::Display for Format {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Format::Scene => f.write_str("a scene file (TOML)"),
            Format::Obj => f.write_str("an OBJ mesh"),
            Format::Gltf => f.write_str("a glTF file (JSON)"),
            Format::Glb => f.write_str("a binary glTF file"),
            Format::Ply => f.write_str("a PLY mesh"),
            Format::Off => f.write_str("an OFF mesh"),
            Format::Stl => f.write_str("an STL mesh"),
            Format::Fbx => f.write_str("an FBX file"),
            Format::Collada => f.write_str("a COLLADA file"),
            Format::Blender => f.write_str("a Blender file"),
            Format::Usd => f.write_str("a USD file"),
            Format::Zip => f.write_str("a ZIP archive (USDZ, 3MF, ...)"),
            Format::Image(kind) => write!(f, "a {kind} image"),
        }
    }
}

/// Formats strata does not read, by extension, with their names.
const NOT_READ: &[(&str, &str)] = &[
    ("fbx", "FBX"),
    ("dae", "COLLADA"),
    ("3ds", "3D Studio"),
    ("blend", "Blender"),
    ("usd", "USD"),
    ("usda", "USD"),
    ("usdc", "USD"),
    ("usdz", "USD"),
    ("abc", "Alembic"),
    ("3mf", "3MF"),
    ("amf", "AMF"),
    ("x3d", "X3D"),
    ("wrl", "VRML"),
    ("vrml", "VRML"),
    ("max", "3ds Max"),
    ("ma", "Maya"),
    ("mb", "Maya"),
    ("c4d", "Cinema 4D"),
    ("lwo", "LightWave"),
    ("lxo", "Modo"),
    ("skp", "SketchUp"),
    ("x", "DirectX"),
    ("dxf", "DXF"),
    ("step", "STEP"),
    ("stp", "STEP"),
    ("iges", "IGES"),
    ("igs", "IGES"),
];

/// The name of a format strata does not read, by its (lower-case) extension.
pub(crate) fn not_read(extension: &str) -> Option<&'static str> {
    NOT_READ
        .iter()
        .find(|(e, _)| *e == extension)
        .map(|(_, name)| *name)
}

/// What strata reads, for messages.
pub(crate) fn what_strata_reads() -> String {
    let meshes = super::SUPPORTED_EXTENSIONS
        .iter()
        .map(|e| format!(".{e}"))
        .collect::<Vec<_>>()
        .join(", ");
    format!("strata reads scene files (.toml) and meshes ({meshes})")
}

fn convert_advice() -> String {
    "convert it to glTF (.glb), for example by importing it into Blender and \
     exporting glTF 2.0"
        .into()
}

/// The lower-case extension of `path` ("" without one).
pub(crate) fn extension_of(path: &Path) -> String {
    path.extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .unwrap_or_default()
}

/// For a file named without an extension: the extension of the mesh format
/// its first bytes tell for sure, as assimp reads such files by content:
/// glTF (JSON or binary), PLY, OFF or STL. Not OBJ, whose first line
/// (`v 1 2 3`, `o name`) is too weak a sign to read a file by.
pub(crate) fn told_mesh_extension(path: &Path) -> Option<&'static str> {
    let (head, len) = read_head(path).ok()?;
    match sniff(&head, len)? {
        found @ (Format::Gltf | Format::Glb | Format::Ply | Format::Off | Format::Stl) => {
            found.extension()
        }
        _ => None,
    }
}

/// The first [`HEAD_BYTES`] of `path` and its length, or why it cannot be read.
pub(crate) fn read_head(path: &Path) -> InputResult<(Vec<u8>, u64)> {
    let cannot = |e: std::io::Error| {
        InputError::file(path, format!("cannot read: {}", super::io_message(&e)))
    };
    let file = std::fs::File::open(path).map_err(cannot)?;
    let len = file.metadata().map_err(cannot)?.len();
    let mut head = Vec::new();
    file.take(HEAD_BYTES)
        .read_to_end(&mut head)
        .map_err(cannot)?;
    Ok((head, len))
}

/// What the first bytes `head` of a file of `len` bytes hold, where they
/// say so surely: a magic number, or a first line that only one format
/// writes. Text that could be several things is `None`.
pub(crate) fn sniff(head: &[u8], len: u64) -> Option<Format> {
    let starts = |magic: &[u8]| head.starts_with(magic);
    let magic: &[(&[u8], Format)] = &[
        (b"glTF", Format::Glb),
        (b"Kaydara FBX Binary", Format::Fbx),
        (b"BLENDER", Format::Blender),
        (b"PXR-USDC", Format::Usd),
        (b"#usda", Format::Usd),
        (b"PK\x03\x04", Format::Zip),
        (b"\x89PNG", Format::Image("PNG")),
        (b"\xff\xd8\xff", Format::Image("JPEG")),
        (b"GIF8", Format::Image("GIF")),
        (b"v/1\x01", Format::Image("OpenEXR")),
        (b"#?RADIANCE", Format::Image("Radiance HDR")),
        (b"#?RGBE", Format::Image("Radiance HDR")),
    ];
    if let Some((_, format)) = magic.iter().find(|(m, _)| starts(m)) {
        return Some(*format);
    }
    if binary_stl_size(head) == Some(len) {
        return Some(Format::Stl);
    }
    let text = head.strip_prefix(b"\xef\xbb\xbf").unwrap_or(head);
    let first = first_line(text)?;
    let word = first.split_whitespace().next().unwrap_or("");
    if first.starts_with('{') {
        return Some(Format::Gltf);
    }
    if first.starts_with('<') {
        return contains(text, b"COLLADA").then_some(Format::Collada);
    }
    if first.starts_with(';') {
        return first.contains("FBX").then_some(Format::Fbx);
    }
    // A TOML key or table first: `solid = true` is no STL file.
    if first.starts_with('[') || first.contains('=') {
        return Some(Format::Scene);
    }
    Some(match word {
        "ply" => Format::Ply,
        "solid" => Format::Stl,
        _ if is_off_keyword(word) => Format::Off,
        // OBJ statements, which TOML would refuse: `v 1 2 3`.
        "v" | "vt" | "vn" | "f" | "o" | "g" | "mtllib" | "usemtl" => Format::Obj,
        _ => return None,
    })
}

/// The length a binary STL file of the triangle count in `head` has.
fn binary_stl_size(head: &[u8]) -> Option<u64> {
    let count = head.get(80..84)?;
    let count = u32::from_le_bytes(count.try_into().ok()?);
    Some(84 + 50 * u64::from(count))
}

/// Whether `word` is an OFF header keyword: `OFF` after any of the
/// prefixes `ST`, `C`, `N`, `4`, `n` (in that order).
pub(crate) fn is_off_keyword(word: &str) -> bool {
    let Some(mut prefix) = word.strip_suffix("OFF") else {
        return false;
    };
    for part in ["ST", "C", "N", "4", "n"] {
        prefix = prefix.strip_prefix(part).unwrap_or(prefix);
    }
    prefix.is_empty()
}

fn contains(haystack: &[u8], needle: &[u8]) -> bool {
    haystack.windows(needle.len()).any(|w| w == needle)
}

/// The first line of `text` that is neither blank nor a `#` comment, if
/// the bytes before its end are text.
fn first_line(text: &[u8]) -> Option<&str> {
    let end = text.iter().position(|&b| b == 0).unwrap_or(text.len());
    let text = match std::str::from_utf8(&text[..end]) {
        Ok(t) => t,
        Err(e) => std::str::from_utf8(&text[..e.valid_up_to()]).ok()?,
    };
    text.lines()
        .map(str::trim)
        .find(|l| !l.is_empty() && !l.starts_with('#'))
}

/// Refuse a mesh file named `.extension` whose first bytes say it holds
/// another format.
pub(crate) fn check_mesh_head(
    path: &Path,
    extension: &str,
    head: &[u8],
    len: u64,
) -> InputResult<()> {
    let Some(named) = Format::of_mesh_extension(extension) else {
        return Ok(());
    };
    match sniff(head, len) {
        // OBJ and TOML are told by a first line only: too weak to
        // overrule a name.
        Some(found)
            if !named.agrees_with(found) && !matches!(found, Format::Obj | Format::Scene) =>
        {
            Err(InputError::file(
                path,
                format!(
                    "holds {found}, not {named} (told by its first bytes); {}",
                    found.advice()
                ),
            ))
        }
        _ => Ok(()),
    }
}

/// Refuse a file given as a scene that is not one: a mesh (render it as a
/// model, or name it in a scene), a format strata does not read, binary
/// data, or, under a name other than `.toml`, text that does not start
/// like TOML.
pub(crate) fn check_scene_head(path: &Path, head: &[u8], len: u64) -> InputResult<()> {
    let extension = extension_of(path);
    let refuse = |message: String| Err(InputError::file(path, message));
    if let Some(format) = Format::of_mesh_extension(&extension) {
        return refuse(format!(
            "is {format}, not a scene file: `strata render {}` renders a model as it \
             comes, and a scene names it in an object (mesh = \"...\")",
            path.display()
        ));
    }
    if let Some(name) = not_read(&extension) {
        return refuse(format!(
            "strata does not read {name} files (.{extension}); {}; {}",
            what_strata_reads(),
            convert_advice()
        ));
    }
    match sniff(head, len) {
        Some(Format::Scene) => Ok(()),
        Some(found) => refuse(format!(
            "holds {found}, not a scene file (told by its first bytes); {}",
            found.advice()
        )),
        None if !is_text(head) => refuse(format!(
            "is not a text file, so not a scene file (TOML text); {}",
            what_strata_reads()
        )),
        // TOML mistakes are the parser's, reported at their lines.
        None if extension == "toml" || first_line(head).is_none() => Ok(()),
        None => refuse(format!(
            "does not look like a scene file (TOML text, usually named .toml); {}",
            what_strata_reads()
        )),
    }
}

/// Whether `head` is text: no NUL byte, and UTF-8 up to where it may have
/// been cut.
fn is_text(head: &[u8]) -> bool {
    if head.contains(&0) {
        return false;
    }
    match std::str::from_utf8(head) {
        Ok(_) => true,
        // A character cut at the end of the head is still text.
        Err(e) => e.error_len().is_none(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn first_bytes_name_the_format() {
        let cases: &[(&[u8], Option<Format>)] = &[
            (b"glTF\x02\x00\x00\x00", Some(Format::Glb)),
            (b"Kaydara FBX Binary  \x00", Some(Format::Fbx)),
            (b"; FBX 7.4.0 project file\n", Some(Format::Fbx)),
            (b"ply\nformat ascii 1.0\n", Some(Format::Ply)),
            (b"OFF\n8 6 12\n", Some(Format::Off)),
            (b"# made by hand\n\nCOFF\n", Some(Format::Off)),
            (b"STCNOFF 3 1 0\n", Some(Format::Off)),
            (b"solid cube\n facet normal 0 0 1\n", Some(Format::Stl)),
            (b"{\"asset\":{\"version\":\"2.0\"}}", Some(Format::Gltf)),
            (b"<?xml version=\"1.0\"?>\n<COLLADA>", Some(Format::Collada)),
            (b"# cube\nv 0 0 0\nv 1 0 0\n", Some(Format::Obj)),
            (b"[render]\nspp = 4\n", Some(Format::Scene)),
            (b"# a scene\nobjects = []\n", Some(Format::Scene)),
            (b"\x89PNG\r\n\x1a\n", Some(Format::Image("PNG"))),
            (b"1.0 2.0 3.0\n", None),
            (b"", None),
        ];
        for (head, format) in cases {
            let len = head.len() as u64;
            assert_eq!(
                sniff(head, len),
                *format,
                "{}",
                String::from_utf8_lossy(head)
            );
        }
        // A binary STL is told by its size: 84 bytes and 50 a triangle.
        let mut stl = vec![0u8; 84 + 2 * 50];
        stl[80] = 2;
        assert_eq!(sniff(&stl, stl.len() as u64), Some(Format::Stl));
        assert_eq!(sniff(&stl, stl.len() as u64 + 1), None);
    }

    #[test]
    fn off_keywords_take_their_prefixes_in_order() {
        for word in [
            "OFF", "COFF", "NOFF", "CNOFF", "STOFF", "STCNOFF", "4OFF", "nOFF",
        ] {
            assert!(is_off_keyword(word), "{word}");
        }
        for word in ["OF", "XOFF", "NCOFF", "off", "OFFS"] {
            assert!(!is_off_keyword(word), "{word}");
        }
    }

    #[test]
    fn a_mesh_named_for_another_format_says_what_it_holds() {
        let p = Path::new("box.obj");
        let e = check_mesh_head(p, "obj", b"glTF\x02\x00\x00\x00", 8).unwrap_err();
        assert_eq!(
            e.to_string(),
            "box.obj: holds a binary glTF file, not an OBJ mesh (told by its first bytes); \
             name it .glb to read it as one"
        );
        let e = check_mesh_head(p, "obj", b"Kaydara FBX Binary  \x00", 30).unwrap_err();
        assert!(e.to_string().contains("holds an FBX file"), "{e}");
        assert!(e.to_string().contains("convert it to glTF"), "{e}");
        // What agrees, or cannot be told, passes to the loader.
        assert!(check_mesh_head(p, "obj", b"v 0 0 0\n", 8).is_ok());
        assert!(check_mesh_head(p, "obj", b"[weird]\n", 8).is_ok());
        let gltf = Path::new("box.gltf");
        assert!(check_mesh_head(gltf, "gltf", b"glTF\x02\x00\x00\x00", 8).is_ok());
        assert!(check_mesh_head(Path::new("a.ply"), "ply", b"OFF\n", 4).is_err());
    }

    #[test]
    fn a_file_given_as_a_scene_must_be_one() {
        let check = |name: &str, head: &[u8]| {
            check_scene_head(Path::new(name), head, head.len() as u64).map_err(|e| e.to_string())
        };
        assert!(check("s.toml", b"[render]\nspp = 4\n").is_ok());
        assert!(check("s.toml", b"").is_ok());
        // TOML mistakes are the parser's to report, at their line.
        assert!(check("s.toml", b"spp 4\n").is_ok());
        assert!(check("scene", b"[render]\n").is_ok());
        assert!(check("scene.txt", b"# only a comment\n").is_ok());
        let e = check("armadillo.off", b"OFF\n").unwrap_err();
        assert!(e.contains("is an OFF mesh, not a scene file"), "{e}");
        let e = check("box.fbx", b"Kaydara FBX Binary  \x00\x1a").unwrap_err();
        assert!(
            e.starts_with("box.fbx: strata does not read FBX files (.fbx)"),
            "{e}"
        );
        assert!(e.contains(".off, .stl"), "{e}");
        let e = check("s.toml", b"Kaydara FBX Binary  \x00").unwrap_err();
        assert!(e.contains("holds an FBX file, not a scene file"), "{e}");
        let e = check("s.toml", b"ply\n").unwrap_err();
        assert!(e.contains("name it .ply"), "{e}");
        let e = check("s.toml", b"v 0 0 0\n").unwrap_err();
        assert!(e.contains("holds an OBJ mesh"), "{e}");
        let e = check("s.toml", b"\x00\x01\x02\xff").unwrap_err();
        assert!(e.contains("not a text file"), "{e}");
        let e = check("points.xyz", b"1.0 2.0 3.0\n").unwrap_err();
        assert!(e.contains("does not look like a scene file"), "{e}");
    }
}
