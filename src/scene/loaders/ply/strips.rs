//! Triangle strips: a `tristrips` element whose `vertex_indices` list
//! runs strips one after another, each ended by −1 (as some older scan
//! files store their triangles; MeshLab's reader takes them too). The
//! fast body readers skip the element; a file that has one is read again
//! here by `ply-rs-bw`'s own parser (such files are few and small beside
//! the scans of faces those readers are for) and its strips are cut into
//! triangles.

use super::super::strip::triangles_of_strip;
use crate::error::{InputError, InputResult};
use ply_rs_bw::parser::Parser;
use ply_rs_bw::ply::{DefaultElement, Header, Property};
use std::path::Path;

/// The element that holds strips.
const STRIPS: &str = "tristrips";

/// Whether `header` declares triangle strips.
pub(super) fn has_strips(header: &Header) -> bool {
    header.elements.contains_key(STRIPS)
}

/// The triangles of every strip of the file `bytes`, whose vertices are
/// `n`, each strip's as `super::super::strip` makes them (the rule glTF's
/// `TRIANGLE_STRIP` follows too); a triangle with a repeated
/// index (what joins strips into one) is dropped. An index below −1 or
/// not below `n` is an error naming the strip element.
pub(super) fn strip_triangles(path: &Path, bytes: &[u8], n: usize) -> InputResult<Vec<[u32; 3]>> {
    let bad = |message: String| InputError::file(path, format!("invalid PLY: {message}"));
    let ply = Parser::<DefaultElement>::new()
        .read_ply(&mut &bytes[..])
        .map_err(|e| bad(e.to_string()))?;
    let mut triangles = Vec::new();
    let Some(elements) = ply.payload.get(STRIPS) else {
        return Ok(triangles);
    };
    for (e, element) in elements.iter().enumerate() {
        let Some(list) = element
            .get("vertex_indices")
            .or_else(|| element.get("vertex_index"))
        else {
            continue;
        };
        let indices = integers(list).ok_or_else(|| {
            bad(format!(
                "{STRIPS} {e}: vertex_indices is not a list of integers"
            ))
        })?;
        let mut strip: Vec<u32> = Vec::new();
        for k in indices.into_iter().chain([-1]) {
            if k == -1 {
                push_strip(&mut triangles, &strip);
                strip.clear();
            } else if k < 0 || k as usize >= n {
                return Err(InputError::file(
                    path,
                    format!(
                        "{STRIPS} {e}: vertex index {k} is out of range (the file has {n} \
                         vertices; −1 ends a strip)"
                    ),
                ));
            } else {
                strip.push(k as u32);
            }
        }
    }
    Ok(triangles)
}

/// The strip `s`'s triangles (`triangles_of_strip`) appended to
/// `triangles`, but for those with a repeated index.
fn push_strip(triangles: &mut Vec<[u32; 3]>, s: &[u32]) {
    triangles
        .extend(triangles_of_strip(s).filter(|t| t[0] != t[1] && t[1] != t[2] && t[0] != t[2]));
}

/// The values of an integer list property, widened; `None` for any other.
fn integers(p: &Property) -> Option<Vec<i64>> {
    fn wide<T: Copy + Into<i64>>(v: &[T]) -> Vec<i64> {
        v.iter().map(|&k| k.into()).collect()
    }
    Some(match p {
        Property::ListChar(v) => wide(v),
        Property::ListUChar(v) => wide(v),
        Property::ListShort(v) => wide(v),
        Property::ListUShort(v) => wide(v),
        Property::ListInt(v) => wide(v),
        Property::ListUInt(v) => wide(v),
        _ => return None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_joins_of_strips_are_dropped() {
        let mut t = Vec::new();
        push_strip(&mut t, &[0, 1, 2, 3, 4]);
        assert_eq!(t, [[0, 1, 2], [1, 3, 2], [2, 3, 4]]);
        // A repeated index joins two strips: its triangles are dropped.
        let mut t = Vec::new();
        push_strip(&mut t, &[0, 1, 2, 2, 5, 6, 7]);
        assert_eq!(t, [[0, 1, 2], [2, 6, 5], [5, 6, 7]]);
    }
}
