//! The body of an ASCII PLY file, read line by line without the generic
//! per-element machinery of `ply-rs-bw` (which builds a property map and a
//! `Vec` per face), since ASCII scans are the large meshes people download.
//!
//! One element per line, its properties in header order: a scalar is one
//! token, a list a count and then that many tokens. Only what the mesh
//! needs is kept (`x y z` of `vertex`, the index list of `face`); every
//! other token is still checked to be a number of its type, so a damaged
//! file fails here as it would in any PLY reader. Errors name the file's
//! line. Floats parse with Rust's correctly rounded `str::parse`, so the
//! positions are the same bits as any exact reader gives; `double`
//! properties round once, from the f64 value, to f32 (or are kept as read,
//! for a [`Point`] of float64).

use super::face::{Face, FaceRows};
use super::point::Point;
use crate::error::{InputError, InputResult};
use ply_rs_bw::ply::{Header, PropertyType, ScalarType};
use rayon::prelude::*;
use std::path::Path;
use wide::u8x32;

/// What a mesh takes from an ASCII PLY body.
#[derive(Default)]
pub(super) struct AsciiBody<P> {
    pub positions: Vec<P>,
    pub faces: FaceRows,
    /// The line of the first vertex, for messages.
    pub first_vertex_line: usize,
}

/// The line of element `index` of the element whose lines start at line
/// `first`, in the ASCII `body` that follows the header's last line,
/// `line` (blank lines carry no element): for a message about an element
/// found bad after parsing.
pub(super) fn line_of_element(
    body: &[u8],
    line: usize,
    first: usize,
    index: usize,
) -> Option<usize> {
    let text = std::str::from_utf8(body).ok()?;
    let (number, _) = (line + 1..)
        .zip(text.lines())
        .skip(first.checked_sub(line + 1)?)
        .filter(|(_, text)| !text.trim_ascii().is_empty())
        .nth(index)?;
    Some(number)
}

/// What to do with one property of an element.
#[derive(Clone, Copy)]
enum Use {
    /// Coordinate `axis` of a vertex.
    Coordinate(usize),
    /// The face's vertex index list.
    Indices,
    /// Checked and dropped.
    Skip,
}

/// Elements per parallel parsing task: large enough that a task's work
/// (about a millisecond) dwarfs its hand-off.
const CHUNK: usize = 1 << 14;

/// Read the body that follows the header, `bytes`; `line` is the number
/// of the header's last line (`end_header`).
///
/// Each element's lines are cut into chunks
/// of [`CHUNK`] elements by one scan for line ends (which also counts
/// lines, for messages), and the chunks are parsed in parallel. Errors
/// are those of a line-by-line reader: the first bad line in file order.
pub(super) fn read_body<P: Point>(
    path: &Path,
    header: &Header,
    bytes: &[u8],
    mut line: usize,
) -> InputResult<AsciiBody<P>> {
    let text = std::str::from_utf8(bytes).map_err(|e| {
        let before = &bytes[..e.valid_up_to()];
        let at = line + 1 + before.iter().filter(|&&b| b == b'\n').count();
        InputError::file(path, "cannot read: not ASCII text".to_string()).on_line(Some(at))
    })?;
    let mut rest = text;
    let mut body = AsciiBody::default();
    for (name, element) in &header.elements {
        let uses: Vec<(Use, &PropertyType)> = element
            .properties
            .iter()
            .map(|(property, def)| {
                let role = match (name.as_str(), property.as_str(), &def.data_type) {
                    ("vertex", "x", PropertyType::Scalar(_)) => Use::Coordinate(0),
                    ("vertex", "y", PropertyType::Scalar(_)) => Use::Coordinate(1),
                    ("vertex", "z", PropertyType::Scalar(_)) => Use::Coordinate(2),
                    ("face", "vertex_indices" | "vertex_index", PropertyType::List(..)) => {
                        Use::Indices
                    }
                    _ => Use::Skip,
                };
                (role, &def.data_type)
            })
            .collect();
        let mut chunks = Vec::new();
        let mut done = 0;
        let mut truncated = false;
        while done < element.count {
            let n = (element.count - done).min(CHUNK);
            // A file that ends early still has its lines checked first, so
            // that an earlier bad line is the one reported.
            let (chunk, lines) = take_elements(rest, n).unwrap_or_else(|| {
                truncated = true;
                (rest, rest.lines().count())
            });
            if name == "vertex" && done == 0 && body.positions.is_empty() {
                body.first_vertex_line = line + 1;
            }
            chunks.push(Chunk {
                text: chunk,
                first_line: line + 1,
                first_element: done,
            });
            rest = &rest[chunk.len()..];
            line += lines;
            done += n;
            if truncated {
                break;
            }
        }
        let element_reader = ElementReader { path, name, uses };
        // Each chunk writes its own part of the element's one array, so no
        // chunk's elements are copied again after parsing.
        let total = done;
        let mut positions = vec![P::default(); if name == "vertex" { total } else { 0 }];
        let mut rows = vec![[0u32; 3]; if name == "face" { total } else { 0 }];
        let mut position_parts: Vec<&mut [P]> = positions.chunks_mut(CHUNK).collect();
        position_parts.resize_with(chunks.len(), Default::default);
        let mut row_parts: Vec<&mut [[u32; 3]]> = rows.chunks_mut(CHUNK).collect();
        row_parts.resize_with(chunks.len(), Default::default);
        let parsed: Vec<InputResult<Vec<(usize, Face)>>> = chunks
            .par_iter()
            .zip(position_parts)
            .zip(row_parts)
            .map(|((chunk, positions), rows)| element_reader.parse(chunk, positions, rows))
            .collect();
        let mut faces = FaceRows {
            rows,
            others: Vec::new(),
        };
        for others in parsed {
            faces.others.extend(others?);
        }
        if body.positions.is_empty() {
            body.positions = positions;
        } else {
            body.positions.extend(positions);
        }
        if body.faces.rows.is_empty() && body.faces.others.is_empty() {
            body.faces = faces;
        } else {
            body.faces.append(faces);
        }
        if truncated {
            return Err(InputError::file(
                path,
                format!(
                    "the file ends before its {} '{name}' elements do",
                    element.count
                ),
            )
            .on_line(Some(line + 1)));
        }
    }
    Ok(body)
}

/// The start of `text` holding its next `n` elements (one a non-blank
/// line; blank lines among them are kept), and how many lines that is;
/// `None` if the text ends first.
///
/// This scan is the serial part of a parallel parse, so it finds line
/// ends 64 bytes at a time ([`line_feeds`]) instead of one search per
/// line (timed in docs/performance.md, "Measurements behind the
/// renderer's defaults").
fn take_elements(text: &str, n: usize) -> Option<(&str, usize)> {
    if n == 0 {
        return Some(("", 0));
    }
    let bytes = text.as_bytes();
    // A last line without a line feed ends where the text does.
    let last = (!bytes.is_empty() && !bytes.ends_with(b"\n")).then_some(bytes.len());
    let ends = bytes
        .chunks(64)
        .enumerate()
        .flat_map(|(k, block)| {
            let mut feeds = line_feeds(block);
            std::iter::from_fn(move || {
                let bit = feeds.trailing_zeros() as usize;
                feeds &= feeds.wrapping_sub(1);
                (bit < 64).then_some(64 * k + bit + 1)
            })
        })
        .chain(last);
    let (mut lines, mut found, mut start) = (0, 0, 0);
    for end in ends {
        if bytes[start..end].iter().any(|b| !b.is_ascii_whitespace()) {
            found += 1;
        }
        lines += 1;
        start = end;
        if found == n {
            return Some((&text[..end], lines));
        }
    }
    None
}

/// Bit `i` set where `block[i]` (at most 64 bytes) is a line feed: one
/// vector compare per 32 bytes of a whole block.
#[inline]
fn line_feeds(block: &[u8]) -> u64 {
    let half = |bytes: &[u8]| -> u64 {
        match <[u8; 32]>::try_from(bytes) {
            Ok(b) => u64::from(u8x32::from(b).simd_eq(u8x32::splat(b'\n')).to_bitmask()),
            Err(_) => bytes
                .iter()
                .enumerate()
                .fold(0, |m, (i, &b)| m | u64::from(b == b'\n') << i),
        }
    };
    let (low, high) = block.split_at(block.len().min(32));
    half(low) | half(high) << 32
}

/// A run of whole lines of one element, where it starts in the file.
struct Chunk<'t> {
    text: &'t str,
    first_line: usize,
    /// The index of its first element within the element's list.
    first_element: usize,
}

/// How to read the lines of one element: its properties' roles and types.
struct ElementReader<'h> {
    path: &'h Path,
    name: &'h str,
    uses: Vec<(Use, &'h PropertyType)>,
}

impl ElementReader<'_> {
    /// Writes the elements of `chunk` (its vertices' positions or its
    /// faces' rows, one a slot, in order) and returns its faces that are
    /// no triangle, with their indices in the element ([`FaceRows`]), or
    /// the error of its first bad line.
    fn parse<P: Point>(
        &self,
        chunk: &Chunk,
        positions: &mut [P],
        rows: &mut [[u32; 3]],
    ) -> InputResult<Vec<(usize, Face)>> {
        let name = self.name;
        let mut others = Vec::new();
        let mut element = 0;
        let mut indices: Vec<u32> = Vec::new();
        for (k, text) in chunk.text.lines().enumerate() {
            // Blank lines carry no element.
            if text.trim_ascii().is_empty() {
                continue;
            }
            let line = chunk.first_line + k;
            let at = |message: String| InputError::file(self.path, message).on_line(Some(line));
            let mut tokens = text.split_ascii_whitespace();
            let mut next = |what: &str| {
                tokens
                    .next()
                    .ok_or_else(|| at(format!("'{name}' element: {what} is missing")))
            };
            let mut position = [0.0f64; 3];
            let mut face = None;
            for &(role, data_type) in &self.uses {
                match (role, data_type) {
                    (Use::Coordinate(axis), PropertyType::Scalar(t)) => {
                        let token = next("a coordinate")?;
                        position[axis] = number(token, t).map_err(&at)?;
                    }
                    (Use::Indices, PropertyType::List(count_type, item_type)) => {
                        let n = count(next("the index count")?, count_type).map_err(&at)?;
                        indices.clear();
                        let mut invalid = None;
                        for _ in 0..n {
                            let k = integer(next("a vertex index")?, item_type).map_err(&at)?;
                            match u32::try_from(k) {
                                Ok(k) => indices.push(k),
                                Err(_) => invalid = invalid.or(Some(k)),
                            }
                        }
                        // A negative index is kept to be reported, not wrapped.
                        face = Some(match invalid {
                            Some(k) => Face::Invalid(k),
                            None => Face::of(&indices),
                        });
                    }
                    (_, PropertyType::Scalar(t)) => {
                        number(next("a value")?, t).map_err(&at)?;
                    }
                    (_, PropertyType::List(count_type, item_type)) => {
                        let n = count(next("a list count")?, count_type).map_err(&at)?;
                        for _ in 0..n {
                            number(next("a list value")?, item_type).map_err(&at)?;
                        }
                    }
                }
            }
            if let Some(extra) = tokens.next() {
                return Err(at(format!(
                    "'{name}' element: unexpected '{extra}' after its {} properties",
                    self.uses.len()
                )));
            }
            match name {
                // Checked once the faces are known: a vertex no face uses
                // may be NaN (`loaders::settle_unused_vertices`).
                "vertex" => positions[element] = P::from_f64s(position),
                "face" => match face.unwrap_or_default() {
                    Face::Triangle(t) => rows[element] = t,
                    other => others.push((chunk.first_element + element, other)),
                },
                _ => {}
            }
            element += 1;
        }
        Ok(others)
    }
}

/// A token of scalar type `t` as f64 (exact for every PLY integer type).
fn number(token: &str, t: &ScalarType) -> Result<f64, String> {
    match t {
        ScalarType::Float => token.parse::<f32>().map(f64::from).map_err(|_| ()),
        ScalarType::Double => token.parse::<f64>().map_err(|_| ()),
        _ => integer(token, t).map(|k| k as f64).map_err(|_| ()),
    }
    .map_err(|()| format!("'{token}' is not a {}", type_name(t)))
}

/// A token of integer type `t`, range-checked.
fn integer(token: &str, t: &ScalarType) -> Result<i64, String> {
    let (lo, hi) = match t {
        ScalarType::Char => (i8::MIN as i64, i8::MAX as i64),
        ScalarType::UChar => (0, u8::MAX as i64),
        ScalarType::Short => (i16::MIN as i64, i16::MAX as i64),
        ScalarType::UShort => (0, u16::MAX as i64),
        ScalarType::Int => (i32::MIN as i64, i32::MAX as i64),
        ScalarType::UInt => (0, u32::MAX as i64),
        ScalarType::Float | ScalarType::Double => {
            return Err(format!("'{token}': a list of {} indices", type_name(t)))
        }
    };
    match token.parse::<i64>() {
        Ok(k) if (lo..=hi).contains(&k) => Ok(k),
        _ => Err(format!("'{token}' is not a {}", type_name(t))),
    }
}

/// A list's length, which must not be negative.
fn count(token: &str, t: &ScalarType) -> Result<usize, String> {
    let n = integer(token, t)?;
    usize::try_from(n).map_err(|_| format!("list length {n} is negative"))
}

fn type_name(t: &ScalarType) -> &'static str {
    match t {
        ScalarType::Char => "char",
        ScalarType::UChar => "uchar",
        ScalarType::Short => "short",
        ScalarType::UShort => "ushort",
        ScalarType::Int => "int",
        ScalarType::UInt => "uint",
        ScalarType::Float => "float",
        ScalarType::Double => "double",
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::stream::{seeded, Draw};

    /// The plain scan: one search for each line's end.
    fn take_elements_by_line(text: &str, n: usize) -> Option<(&str, usize)> {
        let (mut end, mut lines, mut found) = (0, 0, 0);
        while found < n {
            if end >= text.len() {
                return None;
            }
            let line_end = text[end..].find('\n').map_or(text.len(), |k| end + k + 1);
            if !text[end..line_end].trim_ascii().is_empty() {
                found += 1;
            }
            lines += 1;
            end = line_end;
        }
        Some((&text[..end], lines))
    }

    /// The 64-byte scan cuts every text where the line-by-line scan does:
    /// lines of any length across block edges, blank and whitespace-only
    /// lines, CRLF ends, and texts that end without a line feed or early.
    #[test]
    fn block_scan_cuts_where_the_line_scan_does() {
        let mut rng = seeded(11);
        let pieces = ["\n", "\r\n", " \n", "\t \r\n", "1", "-0.25", " ", "3 1 2 0"];
        for round in 0..400 {
            let mut text = String::new();
            let len = rng.range(0.0, 300.0) as usize;
            while text.len() < len {
                text.push_str(pieces[rng.range(0.0, pieces.len() as f32) as usize % pieces.len()]);
            }
            if round % 3 == 0 {
                text.push('\n');
            }
            for n in 0..12 {
                assert_eq!(
                    take_elements(&text, n),
                    take_elements_by_line(&text, n),
                    "{text:?}, {n} elements"
                );
            }
        }
    }
}
