//! The body of a binary PLY file (either endianness), read from the file's
//! bytes in memory straight into the flat arrays a mesh is made of.
//!
//! An element whose records all have one size (scalars only, or lists
//! that all hold three items: the triangles of a scan) is decoded in
//! parallel, record `i` at `i` times the record size, without a value a
//! record allocated; whether every list holds three items is checked
//! first, in one parallel pass over their counts. Any other element (a
//! polygon among the triangles, a file cut short) is walked record by
//! record. The walk reads exactly as `ply-rs-bw` did before it, and
//! fails with the same messages (line numbers count one line per element
//! after the header, as that crate counts them), so a damaged file is
//! reported as before whichever way its elements are read.
//!
//! As before, only `float` and `double` coordinates `x y z` of `vertex`
//! elements are read (other types leave the coordinate 0), and the last
//! `vertex_indices` or `vertex_index` list of integers of `face` elements;
//! a later `vertex` or `face` element replaces an earlier one.

use super::face::Face;
use super::point::Point;
use crate::error::{InputError, InputResult};
use ply_rs_bw::ply::{Encoding, Header, PropertyType, ScalarType};
use rayon::prelude::*;
use std::marker::PhantomData;
use std::path::Path;

/// A PLY scalar type, as a plain copyable value.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub(super) enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    pub(super) fn of(t: &ScalarType) -> Self {
        match t {
            ScalarType::Char => Self::I8,
            ScalarType::UChar => Self::U8,
            ScalarType::Short => Self::I16,
            ScalarType::UShort => Self::U16,
            ScalarType::Int => Self::I32,
            ScalarType::UInt => Self::U32,
            ScalarType::Float => Self::F32,
            ScalarType::Double => Self::F64,
        }
    }

    pub(super) fn size(self) -> usize {
        match self {
            Self::I8 | Self::U8 => 1,
            Self::I16 | Self::U16 => 2,
            Self::I32 | Self::U32 | Self::F32 => 4,
            Self::F64 => 8,
        }
    }

    fn is_integer(self) -> bool {
        !matches!(self, Self::F32 | Self::F64)
    }
}

/// The `N` bytes of `b` at `at`.
#[inline]
fn take<const N: usize>(b: &[u8], at: usize) -> [u8; N] {
    let mut a = [0; N];
    a.copy_from_slice(&b[at..at + N]);
    a
}

/// The float of type `t` at `b[at..]`, as f64 (a `float` widened, so
/// exact); a [`Point`] rounds it once.
#[inline]
fn float<const BIG: bool>(b: &[u8], at: usize, t: Scalar) -> f64 {
    if t == Scalar::F64 {
        let bytes = take(b, at);
        if BIG {
            f64::from_be_bytes(bytes)
        } else {
            f64::from_le_bytes(bytes)
        }
    } else {
        let bytes = take(b, at);
        f64::from(if BIG {
            f32::from_be_bytes(bytes)
        } else {
            f32::from_le_bytes(bytes)
        })
    }
}

/// The integer of type `t` at `b[at..]` (0 for a float type, which no
/// caller passes).
#[inline]
fn integer<const BIG: bool>(b: &[u8], at: usize, t: Scalar) -> i64 {
    macro_rules! read {
        ($ty:ty) => {{
            let bytes = take(b, at);
            (if BIG {
                <$ty>::from_be_bytes(bytes)
            } else {
                <$ty>::from_le_bytes(bytes)
            }) as i64
        }};
    }
    match t {
        Scalar::I8 => read!(i8),
        Scalar::U8 => read!(u8),
        Scalar::I16 => read!(i16),
        Scalar::U16 => read!(u16),
        Scalar::I32 => read!(i32),
        Scalar::U32 => read!(u32),
        Scalar::F32 | Scalar::F64 => 0,
    }
}

/// What the mesh takes from one property.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum Role {
    Coordinate(usize),
    Indices,
    Skip,
}

#[derive(Clone, Copy, Debug)]
enum Kind {
    Scalar(Scalar),
    List { count: Scalar, item: Scalar },
}

#[derive(Clone, Copy, Debug)]
struct Property {
    kind: Kind,
    role: Role,
    /// Where it starts in a record whose lists hold three items each.
    at: usize,
}

/// One element's properties and, if every list's count is an integer, the
/// size of a record whose lists hold three items each.
struct Layout<'h> {
    name: &'h str,
    count: usize,
    properties: Vec<Property>,
    fixed_size: Option<usize>,
}

impl<'h> Layout<'h> {
    fn new(name: &'h str, count: usize, properties: &[(&str, &PropertyType)]) -> Self {
        // A later index list replaces an earlier one: only the last is read.
        let last_indices = properties.iter().rposition(|(p, t)| {
            name == "face"
                && matches!(*p, "vertex_indices" | "vertex_index")
                && matches!(t, PropertyType::List(_, item) if Scalar::of(item).is_integer())
        });
        let mut at = 0;
        let mut fixed = true;
        let properties = properties
            .iter()
            .enumerate()
            .map(|(k, (p, t))| {
                let kind = match t {
                    PropertyType::Scalar(s) => Kind::Scalar(Scalar::of(s)),
                    PropertyType::List(c, i) => Kind::List {
                        count: Scalar::of(c),
                        item: Scalar::of(i),
                    },
                };
                let role = match (name, *p, kind) {
                    ("vertex", "x", Kind::Scalar(Scalar::F32 | Scalar::F64)) => Role::Coordinate(0),
                    ("vertex", "y", Kind::Scalar(Scalar::F32 | Scalar::F64)) => Role::Coordinate(1),
                    ("vertex", "z", Kind::Scalar(Scalar::F32 | Scalar::F64)) => Role::Coordinate(2),
                    _ if Some(k) == last_indices => Role::Indices,
                    _ => Role::Skip,
                };
                let property = Property { kind, role, at };
                at += match kind {
                    Kind::Scalar(s) => s.size(),
                    Kind::List { count, item } => {
                        fixed &= count.is_integer();
                        count.size() + 3 * item.size()
                    }
                };
                property
            })
            .collect();
        Self {
            name,
            count,
            properties,
            fixed_size: fixed.then_some(at),
        }
    }

    fn lists(&self) -> impl Iterator<Item = (usize, Scalar)> + '_ {
        self.properties.iter().filter_map(|p| match p.kind {
            Kind::List { count, .. } => Some((p.at, count)),
            Kind::Scalar(_) => None,
        })
    }

    fn coordinates(&self) -> [Option<(usize, Scalar)>; 3] {
        let mut c = [None; 3];
        for p in &self.properties {
            if let (Role::Coordinate(axis), Kind::Scalar(s)) = (p.role, p.kind) {
                c[axis] = Some((p.at, s));
            }
        }
        c
    }

    fn indices(&self) -> Option<(usize, Scalar)> {
        self.properties.iter().find_map(|p| match (p.role, p.kind) {
            (Role::Indices, Kind::List { count, item }) => Some((p.at + count.size(), item)),
            _ => None,
        })
    }
}

/// What a triangle slot holds for a face with a negative index: found again
/// in the file's bytes when the faces are checked.
const NEGATIVE: [u32; 3] = [u32::MAX; 3];

/// The faces of the last `face` element.
enum Faces<'b> {
    /// Read in parallel: one triangle a face, [`NEGATIVE`] where a face has
    /// a negative index; `records` are the element's bytes, `at` where the
    /// index list's items start in each of its records of `size` bytes.
    Triangles {
        triangles: Vec<[u32; 3]>,
        records: &'b [u8],
        size: usize,
        at: usize,
        item: Scalar,
    },
    /// Walked one by one.
    Walked(Vec<Face>),
}

/// Elements per parallel task at the least: enough that a task's work
/// dwarfs its hand-off.
const MIN_TASK: usize = 1 << 12;

/// Reads the binary `body` that follows `header`, whose first element's
/// line is `line` (`ply-rs-bw`'s count, for messages), and checks it:
/// the mesh's positions and triangles (faces fan-triangulated).
pub(super) fn read_body<P: Point>(
    path: &Path,
    header: &Header,
    body: &[u8],
    line: usize,
) -> InputResult<(Vec<P>, Vec<[u32; 3]>)> {
    if header.encoding == Encoding::BinaryBigEndian {
        read::<true, P>(path, header, body, line)
    } else {
        read::<false, P>(path, header, body, line)
    }
}

fn read<const BIG: bool, P: Point>(
    path: &Path,
    header: &Header,
    body: &[u8],
    mut line: usize,
) -> InputResult<(Vec<P>, Vec<[u32; 3]>)> {
    let bad = |message: String| InputError::file(path, format!("invalid PLY: {message}"));
    let mut positions = Vec::new();
    let mut faces = Faces::Walked(Vec::new());
    let mut at = 0;
    for (name, element) in &header.elements {
        let properties: Vec<(&str, &PropertyType)> = element
            .properties
            .iter()
            .map(|(p, def)| (p.as_str(), &def.data_type))
            .collect();
        let layout = Layout::new(name, element.count, &properties);
        let rest = &body[at..];
        let records = layout
            .fixed_size
            .and_then(|size| Some((size, rest.get(..size.checked_mul(layout.count)?)?)))
            .filter(|&(size, records)| all_lists_hold_three::<BIG>(&layout, records, size));
        match records {
            Some((size, records)) => {
                if name == "vertex" {
                    positions = fixed_positions::<BIG, P>(&layout, records, size);
                } else if let ("face", Some((at, item))) = (name.as_str(), layout.indices()) {
                    faces = Faces::Triangles {
                        triangles: fixed_triangles::<BIG>(records, size, at, item),
                        records,
                        size,
                        at,
                        item,
                    };
                } else if name == "face" {
                    // Faces without indices: no triangles, nothing to check.
                    faces = Faces::Walked(Vec::new());
                }
                at += records.len();
            }
            None => {
                let mut walk = Walk::<BIG, P> {
                    bytes: rest,
                    at: 0,
                    point: PhantomData,
                };
                let walked = walk.element(&layout, line).map_err(bad)?;
                at += walk.at;
                match name.as_str() {
                    "vertex" => positions = walked.positions,
                    "face" => faces = Faces::Walked(walked.faces),
                    _ => {}
                }
            }
        }
        line += element.count;
    }
    // Vertices that are not finite are checked once the faces are known
    // (`loaders::settle_unused_vertices`).
    let n = positions.len();
    let out_of_range = |i: usize, bad: i64| super::face::out_of_range(path, i, bad, n);
    let triangles = match faces {
        Faces::Triangles {
            triangles,
            records,
            size,
            at,
            item,
        } => {
            let first_bad = first_where(&triangles, |t| {
                *t == NEGATIVE || t.iter().any(|&k| k as usize >= n)
            });
            if let Some(i) = first_bad {
                let record = &records[i * size..(i + 1) * size];
                let face =
                    face_of(&[0, 1, 2].map(|k| integer::<BIG>(record, at + k * item.size(), item)));
                if let Some(bad) = face.bad_index(n) {
                    return Err(out_of_range(i, bad));
                }
            }
            triangles
        }
        Faces::Walked(faces) => {
            super::face::triangulate(&faces, n).map_err(|(i, bad)| out_of_range(i, bad))?
        }
    };
    Ok((positions, triangles))
}

/// The index of the first item of `items` that is `bad`, searched in
/// parallel a block at a time (an item at a time, the search's own
/// bookkeeping cost more than the test).
pub(crate) fn first_where<T: Sync>(items: &[T], bad: impl Fn(&T) -> bool + Sync) -> Option<usize> {
    let block = items
        .par_chunks(MIN_TASK)
        .position_first(|block| block.iter().any(&bad))?;
    let start = block * MIN_TASK;
    items[start..].iter().position(bad).map(|i| start + i)
}

/// Whether every list of every record of `records` (fixed `size` bytes
/// each if they do) holds three items, checked in parallel.
fn all_lists_hold_three<const BIG: bool>(layout: &Layout, records: &[u8], size: usize) -> bool {
    let lists: Vec<(usize, Scalar)> = layout.lists().collect();
    if lists.is_empty() || size == 0 {
        return true;
    }
    records
        .par_chunks_exact(size)
        .with_min_len(MIN_TASK)
        .all(|r| lists.iter().all(|&(at, t)| integer::<BIG>(r, at, t) == 3))
}

fn fixed_positions<const BIG: bool, P: Point>(
    layout: &Layout,
    records: &[u8],
    size: usize,
) -> Vec<P> {
    let coordinates = layout.coordinates();
    let mut positions = Vec::new();
    if size == 0 {
        // Records of no bytes: a vertex of no coordinates each.
        positions.resize(layout.count, P::default());
        return positions;
    }
    records
        .par_chunks_exact(size)
        .with_min_len(MIN_TASK)
        .map(|r| P::from_f64s(coordinates.map(|c| c.map_or(0.0, |(at, t)| float::<BIG>(r, at, t)))))
        .collect_into_vec(&mut positions);
    positions
}

fn fixed_triangles<const BIG: bool>(
    records: &[u8],
    size: usize,
    at: usize,
    item: Scalar,
) -> Vec<[u32; 3]> {
    let mut triangles = Vec::new();
    let step = item.size();
    records
        .par_chunks_exact(size)
        .with_min_len(MIN_TASK)
        .map(|r| {
            let k = [0, 1, 2].map(|j| integer::<BIG>(r, at + j * step, item));
            if k.iter().any(|&k| k < 0) {
                NEGATIVE
            } else {
                k.map(|k| k as u32)
            }
        })
        .collect_into_vec(&mut triangles);
    triangles
}

/// The face of the index list `k` as the old reader kept it: its first
/// negative index, or its indices.
fn face_of(k: &[i64]) -> Face {
    if let Some(&negative) = k.iter().find(|&&k| k < 0) {
        return Face::Invalid(negative);
    }
    // Items of the integer types that are not negative fit a u32.
    match *k {
        [a, b, c] => Face::Triangle([a as u32, b as u32, c as u32]),
        _ => Face::Polygon(k.iter().map(|&k| k as u32).collect()),
    }
}

/// What one walked element gives the mesh.
#[derive(Default)]
struct Walked<P> {
    positions: Vec<P>,
    faces: Vec<Face>,
}

/// A walk over an element's records, one value at a time.
struct Walk<'b, const BIG: bool, P> {
    bytes: &'b [u8],
    at: usize,
    /// The type the walk keeps positions in.
    point: PhantomData<P>,
}

/// Why a value could not be read: the end of the file (with the message
/// the old reader gave it), or another error (its message).
enum Stop {
    End(String),
    Invalid(String),
}

/// What `std::io::Read::read_exact` says at the end of a file.
const FILL: &str = "failed to fill whole buffer";

impl<const BIG: bool, P: Point> Walk<'_, BIG, P> {
    /// The next `n` bytes.
    fn bytes(&mut self, n: usize) -> Result<&[u8], Stop> {
        let b = self
            .bytes
            .get(self.at..self.at + n)
            .ok_or_else(|| Stop::End(FILL.to_string()))?;
        self.at += n;
        Ok(b)
    }

    fn integer(&mut self, t: Scalar) -> Result<i64, Stop> {
        Ok(integer::<BIG>(self.bytes(t.size())?, 0, t))
    }

    /// A list's length, as the old reader read and checked it.
    fn count(&mut self, t: Scalar) -> Result<usize, Stop> {
        let negative = |bits| Stop::Invalid(format!("List length cannot be negative ({bits})."));
        let n = match t {
            Scalar::F32 | Scalar::F64 => {
                let name = if t == Scalar::F32 { "float" } else { "double" };
                return Err(Stop::Invalid(format!(
                    "Index of list must be an integer type, {name} declared in ScalarType."
                )));
            }
            _ => self.integer(t)?,
        };
        match (t, n < 0) {
            (Scalar::I8, true) => Err(negative("i8")),
            (Scalar::I16, true) => Err(negative("i16")),
            (Scalar::I32, true) => Err(negative("i32")),
            _ => Ok(n as usize),
        }
    }

    /// Reads the element of `layout`, whose first record is on `line`, or
    /// the message of the old reader's error.
    fn element(&mut self, layout: &Layout, line: usize) -> Result<Walked<P>, String> {
        let mut walked = Walked::default();
        let mut items = Vec::new();
        for i in 0..layout.count {
            let mut position = [0.0f64; 3];
            let mut face = Face::Empty;
            let record = self.record(layout, &mut position, &mut face, &mut items);
            match record {
                Ok(()) => {}
                Err(Stop::End(inner)) => {
                    return Err(format!(
                        "Line {}: Unexpected end of file while reading binary element '{}' (expected {}, got {i}).\n\tError: {inner}",
                        line + i,
                        layout.name,
                        layout.count
                    ))
                }
                Err(Stop::Invalid(message)) => return Err(format!("Line {}: {message}", line + i)),
            }
            match layout.name {
                "vertex" => walked.positions.push(P::from_f64s(position)),
                "face" => walked.faces.push(face),
                _ => {}
            }
        }
        Ok(walked)
    }

    fn record(
        &mut self,
        layout: &Layout,
        position: &mut [f64; 3],
        face: &mut Face,
        items: &mut Vec<i64>,
    ) -> Result<(), Stop> {
        for p in &layout.properties {
            match p.kind {
                Kind::Scalar(t) => {
                    let b = self.bytes(t.size())?;
                    if let Role::Coordinate(axis) = p.role {
                        position[axis] = float::<BIG>(b, 0, t);
                    }
                }
                Kind::List { count, item } => {
                    let n = self.count(count)?;
                    items.clear();
                    for j in 0..n {
                        let b = self.bytes(item.size()).map_err(|_| {
                            Stop::End(format!(
                                "Couldn't find a list element at index {j}.\n\tError: {FILL}"
                            ))
                        })?;
                        if p.role == Role::Indices {
                            items.push(integer::<BIG>(b, 0, item));
                        }
                    }
                    if p.role == Role::Indices {
                        *face = face_of(items);
                    }
                }
            }
        }
        Ok(())
    }
}
