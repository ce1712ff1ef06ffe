//! A triangle strip's triangles, as glTF's `TRIANGLE_STRIP` primitives and
//! PLY's `tristrips` elements both define them: one rule, so that a strip
//! faces the same way from either file.

/// Triangle k of the strip `order` is its indices k, k + 1, k + 2, the odd
/// ones taken as k, k + 2, k + 1, so that every triangle turns the same way
/// as the first.
pub(super) fn triangles_of_strip(order: &[u32]) -> impl Iterator<Item = [u32; 3]> + '_ {
    (0..order.len().saturating_sub(2)).map(|k| {
        if k % 2 == 0 {
            [order[k], order[k + 1], order[k + 2]]
        } else {
            [order[k], order[k + 2], order[k + 1]]
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_triangle_of_a_strip_turns_the_same_way() {
        // A row of quads zig-zagged as a strip.
        let p = |i: u32| [f64::from(i / 2), f64::from(i % 2)];
        let t: Vec<[u32; 3]> = triangles_of_strip(&[0, 1, 2, 3, 4, 5, 6]).collect();
        assert_eq!(t.len(), 5);
        let turn = |tri: &[u32; 3]| {
            let [a, b, c] = tri.map(p);
            (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
        };
        for tri in &t {
            assert_eq!(turn(tri), turn(&t[0]), "{tri:?} turns the other way");
        }
        assert_eq!(t[..3], [[0, 1, 2], [1, 3, 2], [2, 3, 4]]);
        assert_eq!(
            triangles_of_strip(&[4, 5]).count(),
            0,
            "two indices make no triangle"
        );
    }
}
