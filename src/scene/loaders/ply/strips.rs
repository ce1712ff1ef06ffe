//! Triangle strips: a `tristrips` element whose `vertex_indices` list
//! runs strips one after another, each ended by −1 (as some older scan
//! files store their triangles; MeshLab's reader takes them too). The
//! fast body readers skip the element; a file that has one is read again
//! here by `ply-rs-bw`'s own parser (such files are few and small beside
//! the scans of faces those readers are for) and its strips are cut into
//! triangles.

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
/// `n`: triangle k of a strip is its indices k, k + 1, k + 2, the odd
/// ones taken as k, k + 2, k + 1 so that every triangle turns the same
/// way (as glTF's `TRIANGLE_STRIP` does); a triangle with a repeated
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

/// The strip `s`'s triangles appended to `triangles`, as
/// [`strip_triangles`] says.
fn push_strip(triangles: &mut Vec<[u32; 3]>, s: &[u32]) {
    for k in 0..s.len().saturating_sub(2) {
        let t = if k % 2 == 0 {
            [s[k], s[k + 1], s[k + 2]]
        } else {
            [s[k], s[k + 2], s[k + 1]]
        };
        if t[0] != t[1] && t[1] != t[2] && t[0] != t[2] {
            triangles.push(t);
        }
    }
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
    fn strips_turn_every_triangle_the_same_way_and_drop_the_joins() {
        // A row of quads zig-zagged as a strip: every triangle's normal
        // points the same way.
        let p = |i: u32| [f64::from(i / 2), f64::from(i % 2)];
        let mut t = Vec::new();
        push_strip(&mut t, &[0, 1, 2, 3, 4, 5, 6]);
        assert_eq!(t.len(), 5);
        let turn = |tri: &[u32; 3]| {
            let [a, b, c] = tri.map(p);
            (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
        };
        for tri in &t {
            assert_eq!(turn(tri), turn(&t[0]), "{tri:?} turns the other way");
        }
        let mut t = Vec::new();
        push_strip(&mut t, &[0, 1, 2, 3, 4]);
        assert_eq!(t, [[0, 1, 2], [1, 3, 2], [2, 3, 4]]);
        // A repeated index joins two strips: its triangles are dropped.
        let mut t = Vec::new();
        push_strip(&mut t, &[0, 1, 2, 2, 5, 6, 7]);
        assert_eq!(t, [[0, 1, 2], [2, 6, 5], [5, 6, 7]]);
        let mut t = Vec::new();
        push_strip(&mut t, &[4, 5]);
        assert!(t.is_empty(), "two indices make no triangle");
    }
}
