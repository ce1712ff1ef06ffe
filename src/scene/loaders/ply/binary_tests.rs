//! The binary reader against the one it replaced (`ply-rs-bw`'s element
//! reader, kept here as it was): the same positions and triangles, or the
//! same error message, on generated files of every shape the reader
//! distinguishes, whole and cut short.

use super::super::test_files::{temp_dir, write};
use super::binary::Scalar;
use super::load_ply;
use crate::sampling::stream::{seeded, StreamRng};
use glam::Vec3;
use ply_rs_bw::parser::{Parser, Reader};
use ply_rs_bw::ply::{Encoding, PropertyAccess, PropertyAccessResult};
use rand::RngExt;
use std::io::BufReader;
use std::path::Path;

// ---- The reference: the loader's binary path before this reader. ----

#[derive(Default)]
struct Vertex([f32; 3]);

impl PropertyAccess for Vertex {
    fn new() -> Self {
        Self::default()
    }
    fn set_float(&mut self, name: &str, v: f32) -> PropertyAccessResult {
        self.set(name, v)
    }
    fn set_double(&mut self, name: &str, v: f64) -> PropertyAccessResult {
        self.set(name, v as f32)
    }
}

impl Vertex {
    fn set(&mut self, name: &str, v: f32) -> PropertyAccessResult {
        match name {
            "x" => self.0[0] = v,
            "y" => self.0[1] = v,
            "z" => self.0[2] = v,
            _ => {}
        }
        PropertyAccessResult::Ignored
    }
}

#[derive(Default)]
struct RefFace(Vec<i64>, bool);

impl RefFace {
    fn set<T: Into<i64>>(&mut self, name: &str, v: Vec<T>) -> PropertyAccessResult {
        if name == "vertex_indices" || name == "vertex_index" {
            *self = RefFace(v.into_iter().map(Into::into).collect(), true);
        }
        PropertyAccessResult::Ignored
    }
}

impl PropertyAccess for RefFace {
    fn new() -> Self {
        Self::default()
    }
    fn set_list_char(&mut self, n: &str, v: Vec<i8>) -> PropertyAccessResult {
        self.set(n, v)
    }
    fn set_list_uchar(&mut self, n: &str, v: Vec<u8>) -> PropertyAccessResult {
        self.set(n, v)
    }
    fn set_list_short(&mut self, n: &str, v: Vec<i16>) -> PropertyAccessResult {
        self.set(n, v)
    }
    fn set_list_ushort(&mut self, n: &str, v: Vec<u16>) -> PropertyAccessResult {
        self.set(n, v)
    }
    fn set_list_int(&mut self, n: &str, v: Vec<i32>) -> PropertyAccessResult {
        self.set(n, v)
    }
    fn set_list_uint(&mut self, n: &str, v: Vec<u32>) -> PropertyAccessResult {
        self.set(n, v)
    }
}

type Mesh = (Vec<Vec3>, Vec<[u32; 3]>);

/// What the old loader gave for a binary file: its mesh, or its message
/// (after the file's name), as an [`InputError`] shows it.
fn reference(path: &Path) -> Result<Mesh, String> {
    old_loader(path).map_err(|message| {
        let e = crate::error::InputError::file(path, message);
        e.to_string()[format!("{}: ", e.file).len()..].to_string()
    })
}

fn old_loader(path: &Path) -> Result<Mesh, String> {
    let file = std::fs::File::open(path).unwrap();
    let file_len = file.metadata().unwrap().len();
    let mut reader = Reader::new(BufReader::new(file));
    let bad = |e: &dyn std::fmt::Display| format!("invalid PLY: {e}");
    let vparser = Parser::<Vertex>::new();
    let fparser = Parser::<RefFace>::new();
    let header = vparser.read_header(&mut reader).map_err(|e| bad(&e))?;
    assert_ne!(header.encoding, Encoding::Ascii);
    for (name, e) in &header.elements {
        let min: u64 = e
            .properties
            .values()
            .map(|p| match &p.data_type {
                ply_rs_bw::ply::PropertyType::Scalar(t)
                | ply_rs_bw::ply::PropertyType::List(t, _) => Scalar::of(t).size() as u64,
            })
            .sum::<u64>()
            .max(1);
        if (e.count as u64).saturating_mul(min) > file_len {
            return Err(format!(
                "the header claims {} '{name}' elements, more than the file's {file_len} bytes can hold",
                e.count
            ));
        }
    }
    let mut positions = Vec::new();
    let mut faces = Vec::new();
    for (name, def) in &header.elements {
        match name.as_str() {
            "vertex" => {
                positions = vparser
                    .read_payload_for_element(&mut reader, def, &header)
                    .map_err(|e| bad(&e))?
                    .into_iter()
                    .map(|v| Vec3::from(v.0))
                    .collect();
            }
            "face" => {
                faces = fparser
                    .read_payload_for_element(&mut reader, def, &header)
                    .map_err(|e| bad(&e))?;
            }
            _ => {
                vparser
                    .read_payload_for_element(&mut reader, def, &header)
                    .map_err(|e| bad(&e))?;
            }
        }
    }
    let n = positions.len();
    let mut indices = Vec::new();
    for (i, RefFace(f, set)) in faces.iter().enumerate() {
        if !set {
            continue;
        }
        let bad = f
            .iter()
            .find(|&&k| k < 0)
            .or_else(|| f.iter().find(|&&k| k as usize >= n));
        if let Some(bad) = bad {
            return Err(format!(
                "face {i}: vertex index {bad} is out of range (the file has {n} vertices)"
            ));
        }
        for k in 1..f.len().saturating_sub(1) {
            indices.push([f[0], f[k], f[k + 1]].map(|k| k as u32));
        }
    }
    // Once the faces are read: a vertex a face uses must be finite; one no
    // face uses takes the first triangle's first vertex's place.
    let used = |i: usize| indices.iter().flatten().any(|&k| k as usize == i);
    let not_finite = |i: usize| !positions[i].is_finite();
    if let Some(i) = (0..n).find(|&i| not_finite(i) && used(i)) {
        return Err(format!(
            "vertex {i} is not finite: {} (a face uses it)",
            positions[i]
        ));
    }
    if let Some(first) = indices.first().map(|t| positions[t[0] as usize]) {
        for p in positions.iter_mut().filter(|p| !p.is_finite()) {
            *p = first;
        }
    }
    Ok((positions, indices))
}

/// What the loader gives now, in the same terms.
fn loaded(path: &Path) -> Result<Mesh, String> {
    match load_ply(path) {
        Ok(mut a) => {
            let m = a.meshes.remove(0);
            Ok((m.positions, m.indices))
        }
        Err(e) => {
            let text = e.to_string();
            let prefix = format!("{}: ", e.file);
            assert!(text.starts_with(&prefix), "{text}");
            Err(text[prefix.len()..].to_string())
        }
    }
}

/// Both loaders agree on `bytes`, bit for bit; returns what they gave.
fn agree(name: &str, bytes: &[u8]) -> Result<Mesh, String> {
    let dir = temp_dir("ply-binary");
    let path = write(&dir, name, bytes);
    let (new, old) = (loaded(&path), reference(&path));
    fn bits(m: &Result<Mesh, String>) -> Result<(Vec<u32>, Vec<[u32; 3]>), String> {
        m.clone().map(|(p, i)| {
            let p: Vec<u32> = p
                .iter()
                .flat_map(|v| v.to_array())
                .map(f32::to_bits)
                .collect();
            (p, i)
        })
    }
    assert_eq!(bits(&new), bits(&old), "{name}");
    new
}

// ---- Generated files. ----

const TYPES: [(&str, Scalar); 8] = [
    ("char", Scalar::I8),
    ("uchar", Scalar::U8),
    ("short", Scalar::I16),
    ("ushort", Scalar::U16),
    ("int", Scalar::I32),
    ("uint", Scalar::U32),
    ("float", Scalar::F32),
    ("double", Scalar::F64),
];

fn pick(rng: &mut StreamRng, n: usize) -> usize {
    (rng.random::<u32>() as usize) % n
}

/// A property of a generated element.
#[derive(Clone)]
enum Prop {
    Scalar(String, Scalar),
    List(String, Scalar, Scalar),
}

/// Writers of values in the file's byte order.
struct Out {
    big: bool,
    bytes: Vec<u8>,
}

impl Out {
    fn value(&mut self, t: Scalar, v: f64) {
        macro_rules! put {
            ($x:expr) => {
                if self.big {
                    self.bytes.extend($x.to_be_bytes())
                } else {
                    self.bytes.extend($x.to_le_bytes())
                }
            };
        }
        match t {
            Scalar::I8 => put!(v as i8),
            Scalar::U8 => put!(v as u8),
            Scalar::I16 => put!(v as i16),
            Scalar::U16 => put!(v as u16),
            Scalar::I32 => put!(v as i32),
            Scalar::U32 => put!(v as u32),
            Scalar::F32 => put!(v as f32),
            Scalar::F64 => put!(v),
        }
    }
}

/// What kinds of damage or variety a generated file has.
#[derive(Clone, Copy, Default)]
struct Shape {
    big: bool,
    /// Faces with 4 or 2 indices among the triangles.
    polygons: bool,
    /// A vertex whose y is NaN.
    nan_vertex: Option<usize>,
    /// A face with an index past the vertices, or a negative one.
    bad_face: Option<(usize, i64)>,
}

/// A random binary PLY of `nv` vertices and `nf` faces: coordinates float
/// or double among extra properties (normals, colours, a list), faces with
/// extra scalars around the index list of random count and item types,
/// and an extra element before or after the faces.
fn generate(rng: &mut StreamRng, nv: usize, nf: usize, shape: Shape) -> Vec<u8> {
    let scalar = |rng: &mut StreamRng| TYPES[pick(rng, 8)].1;
    let name_of = |t: Scalar| TYPES.iter().find(|(_, s)| *s == t).unwrap().0;
    // Vertex properties: x, y, z in order among extras.
    let mut vprops = Vec::new();
    for (k, axis) in ["x", "y", "z"].into_iter().enumerate() {
        for e in 0..pick(rng, 3) {
            vprops.push(match pick(rng, 4) {
                0 => Prop::List(format!("extra{k}{e}"), Scalar::U8, scalar(rng)),
                _ => Prop::Scalar(format!("n{k}{e}"), scalar(rng)),
            });
        }
        let t = if pick(rng, 2) == 0 {
            Scalar::F32
        } else {
            Scalar::F64
        };
        vprops.push(Prop::Scalar(axis.to_string(), t));
    }
    // Index types wide enough for the vertex count, counts any integer.
    let items: Vec<Scalar> = [
        Scalar::I8,
        Scalar::U8,
        Scalar::I16,
        Scalar::U16,
        Scalar::I32,
        Scalar::U32,
    ]
    .into_iter()
    .filter(|t| match t {
        Scalar::I8 => nv <= 127,
        Scalar::U8 => nv <= 255,
        Scalar::I16 => nv <= 32767,
        Scalar::U16 => nv <= 65535,
        _ => true,
    })
    .collect();
    let item = items[pick(rng, items.len())];
    let count = [
        Scalar::U8,
        Scalar::I8,
        Scalar::U16,
        Scalar::I32,
        Scalar::U32,
    ][pick(rng, 5)];
    let mut fprops = Vec::new();
    for e in 0..pick(rng, 3) {
        fprops.push(Prop::Scalar(format!("flag{e}"), scalar(rng)));
    }
    let index_name = if pick(rng, 2) == 0 {
        "vertex_indices"
    } else {
        "vertex_index"
    };
    fprops.push(Prop::List(index_name.to_string(), count, item));
    for e in 0..pick(rng, 2) {
        fprops.push(Prop::Scalar(format!("tail{e}"), scalar(rng)));
    }
    let edges = pick(rng, 3);
    let edges_first = pick(rng, 2) == 0;

    let mut head = format!(
        "ply\nformat {} 1.0\ncomment generated\nelement vertex {nv}\n",
        if shape.big {
            "binary_big_endian"
        } else {
            "binary_little_endian"
        }
    );
    let declare = |head: &mut String, props: &[Prop]| {
        for p in props {
            match p {
                Prop::Scalar(n, t) => *head += &format!("property {} {n}\n", name_of(*t)),
                Prop::List(n, c, t) => {
                    *head += &format!("property list {} {} {n}\n", name_of(*c), name_of(*t))
                }
            }
        }
    };
    declare(&mut head, &vprops);
    let eprops = [
        Prop::List("pair".into(), Scalar::U8, Scalar::I32),
        Prop::Scalar("w".into(), Scalar::F32),
    ];
    let edge_head = format!("element edge {edges}\n");
    if edges_first {
        head += &edge_head;
        declare(&mut head, &eprops);
    }
    head += &format!("element face {nf}\n");
    declare(&mut head, &fprops);
    if !edges_first {
        head += &edge_head;
        declare(&mut head, &eprops);
    }
    head += "end_header\n";

    let mut out = Out {
        big: shape.big,
        bytes: head.into_bytes(),
    };
    let small = |rng: &mut StreamRng, t: Scalar| -> f64 {
        match t {
            Scalar::F32 | Scalar::F64 => rng.random::<f32>() as f64 * 2.0 - 1.0,
            _ => pick(rng, 100) as f64,
        }
    };
    for i in 0..nv {
        for p in &vprops {
            match p {
                Prop::Scalar(n, t) => {
                    let v = match n.as_str() {
                        "y" if shape.nan_vertex == Some(i) => f64::NAN,
                        "x" | "y" | "z" => rng.random::<f32>() as f64 * 10.0 - 5.0,
                        _ => small(rng, *t),
                    };
                    out.value(*t, v);
                }
                Prop::List(_, c, t) => {
                    out.value(*c, 3.0);
                    for _ in 0..3 {
                        let v = small(rng, *t);
                        out.value(*t, v);
                    }
                }
            }
        }
    }
    let write_edges = |out: &mut Out, rng: &mut StreamRng| {
        for _ in 0..edges {
            let n = if shape.polygons { pick(rng, 4) } else { 3 };
            out.value(Scalar::U8, n as f64);
            for _ in 0..n {
                out.value(Scalar::I32, pick(rng, 50) as f64);
            }
            out.value(Scalar::F32, 0.5);
        }
    };
    if edges_first {
        write_edges(&mut out, rng);
    }
    for f in 0..nf {
        for p in &fprops {
            match p {
                Prop::Scalar(_, t) => {
                    let v = small(rng, *t);
                    out.value(*t, v);
                }
                Prop::List(_, c, t) => {
                    let n = if shape.polygons && pick(rng, 5) == 0 {
                        [2, 4, 5][pick(rng, 3)]
                    } else {
                        3
                    };
                    out.value(*c, n as f64);
                    let bad_at = pick(rng, n);
                    for j in 0..n {
                        let k = match shape.bad_face {
                            // An unsigned type holds no negative index:
                            // one past the vertices instead.
                            Some((face, bad)) if face == f && j == bad_at => {
                                if bad < 0 && matches!(t, Scalar::U8 | Scalar::U16 | Scalar::U32) {
                                    nv as f64
                                } else {
                                    bad as f64
                                }
                            }
                            _ => pick(rng, nv) as f64,
                        };
                        out.value(*t, k);
                    }
                }
            }
        }
    }
    if !edges_first {
        write_edges(&mut out, rng);
    }
    out.bytes
}

/// Small files of every shape agree whole and cut at every byte.
#[test]
fn small_files_agree_whole_and_cut_anywhere() {
    let mut rng = seeded(49);
    for round in 0..120 {
        let (nv, nf) = (5 + pick(&mut rng, 20), 3 + pick(&mut rng, 10));
        let shape = Shape {
            big: round % 2 == 1,
            polygons: round % 3 == 0,
            nan_vertex: (round % 7 == 2).then_some(3),
            bad_face: match round % 5 {
                1 => Some((4.min(nf - 1), 30)),
                3 => Some((2, -2)),
                _ => None,
            },
        };
        let bytes = generate(&mut rng, nv, nf, shape);
        let whole = agree("whole.ply", &bytes);
        if shape.nan_vertex.is_none() && shape.bad_face.is_none() {
            let (positions, triangles) = whole.unwrap();
            assert_eq!(positions.len(), nv);
            if !shape.polygons {
                assert_eq!(triangles.len(), nf);
            }
        } else if let (Some(v), None) = (shape.nan_vertex, shape.bad_face) {
            // An error exactly where a face uses the NaN vertex.
            match whole {
                Ok((positions, triangles)) => {
                    assert!(!triangles.iter().flatten().any(|&k| k as usize == v));
                    assert!(positions.iter().all(|p| p.is_finite()));
                }
                Err(e) => assert!(e.ends_with("(a face uses it)"), "{e}"),
            }
        } else {
            assert!(whole.is_err());
        }
        let body = bytes
            .windows(11)
            .position(|w| w == b"end_header\n")
            .unwrap()
            + 11;
        for cut in body..bytes.len() {
            agree("cut.ply", &bytes[..cut]).unwrap_err();
        }
    }
}

/// Files big enough to be read in many parallel tasks agree with the
/// reference on any thread count, with the bad vertex or face anywhere,
/// including where tasks meet.
#[test]
fn large_files_agree_in_parallel() {
    let mut rng = seeded(7);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(3)
        .build()
        .unwrap();
    let (nv, nf) = (40_000, 70_001);
    for round in 0..12 {
        let at = [0, 4095, 4096, 12_288, 40_000, 70_000][round % 6];
        let shape = Shape {
            big: round % 2 == 0,
            polygons: round % 4 == 3,
            nan_vertex: (round % 3 == 1).then_some(at.min(nv - 1)),
            bad_face: match round % 3 {
                0 => Some((at, nv as i64)),
                2 => Some((at, -1)),
                _ => None,
            },
        };
        let bytes = generate(&mut rng, nv, nf, shape);
        let got = pool.install(|| agree("large.ply", &bytes));
        let message = got.unwrap_err();
        let what = match (shape.nan_vertex, shape.bad_face) {
            (Some(i), _) => format!("vertex {i} is not finite"),
            (None, Some((f, _))) => format!("face {f}: vertex index"),
            (None, None) => unreachable!(),
        };
        assert!(message.starts_with(&what), "{message}");
        // Cut inside the faces: the walk names the element and record.
        let cut = bytes.len() - 1000;
        let message = pool
            .install(|| agree("cut.ply", &bytes[..cut]))
            .unwrap_err();
        assert!(message.contains("Unexpected end of file"), "{message}");
    }
    // And whole, undamaged, on one thread and three.
    let bytes = generate(&mut rng, nv, nf, Shape::default());
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let a = one.install(|| agree("ok.ply", &bytes)).unwrap();
    let b = pool.install(|| agree("ok.ply", &bytes)).unwrap();
    assert_eq!(a, b);
    assert_eq!(a.1.len(), nf);
}

/// List counts that are negative or not integers fail as they did.
#[test]
fn bad_list_counts_fail_as_before() {
    for (count, bytes) in [
        ("char", vec![0xff]),
        ("short", vec![0xff, 0xff]),
        ("int", vec![0xff, 0xff, 0xff, 0xff]),
        ("float", vec![0, 0, 0x40, 0x40]),
        ("double", vec![0, 0, 0, 0, 0, 0, 8, 0x40]),
    ] {
        let mut file = format!(
            "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list {count} int vertex_indices\nend_header\n"
        )
        .into_bytes();
        for v in [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0] {
            file.extend(v.to_le_bytes());
        }
        file.extend(&bytes);
        for k in [0i32, 1, 2] {
            file.extend(k.to_le_bytes());
        }
        let message = agree("count.ply", &file).err().unwrap_or_default();
        // A header may refuse a float count type; where it does not, the
        // body does.
        assert!(message.starts_with("invalid PLY"), "{count}: {message}");
    }
}
