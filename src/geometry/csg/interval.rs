//! Inside-intervals of a solid along a line, and their boolean combination
//! (the classification step of Roth 1982, "Ray Casting for Modeling Solids").
//!
//! A solid meets a line in a sorted list of disjoint [`Span`]s. Spans are
//! half-open, `[start, end)`, everywhere and always: then a solid minus an
//! identical copy of itself leaves `[t0, t0)` and `[t1, t1)`, which are
//! empty and dropped, and two solids that touch at one point merge into one
//! span with no boundary between them. Every list handed to [`combine`] or
//! built with [`push_span`] is *canonical*: spans are non-empty and each one
//! ends strictly before the next begins.

/// Bit 31 of [`Boundary::code`]: the surface's outward normal must be
/// flipped to point out of the combined solid.
pub const FLIP: u32 = 1 << 31;

/// A point where the line crosses an operand's surface.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Boundary {
    pub t: f32,
    /// Which surface (a CSG part id) in the low 31 bits, plus [`FLIP`].
    pub code: u32,
    /// Barycentrics of v1 and v2 when the surface is a mesh triangle.
    pub u: f32,
    pub v: f32,
}

impl Boundary {
    pub fn new(t: f32, code: u32) -> Self {
        Self {
            t,
            code,
            u: 0.0,
            v: 0.0,
        }
    }

    fn flipped(mut self) -> Self {
        self.code ^= FLIP;
        self
    }
}

/// The line is inside the solid for `start.t <= t < end.t`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Span {
    pub start: Boundary,
    pub end: Boundary,
}

/// The boolean operators.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CsgOp {
    Union,
    Intersection,
    /// `a` minus `b`.
    Difference,
}

impl CsgOp {
    #[inline]
    pub fn apply(self, in_a: bool, in_b: bool) -> bool {
        match self {
            CsgOp::Union => in_a || in_b,
            CsgOp::Intersection => in_a && in_b,
            CsgOp::Difference => in_a && !in_b,
        }
    }
}

/// Append `[start, end)` to the canonical list `spans[from..]`, keeping it
/// canonical: an empty (or NaN) span is dropped, and a span that touches or
/// overlaps the last one extends it. Spans must arrive sorted by start.
#[inline]
pub fn push_span(spans: &mut Vec<Span>, from: usize, start: Boundary, end: Boundary) {
    // No comparison with NaN is true, so this drops NaN spans too.
    let non_empty = start.t < end.t;
    if !non_empty {
        return;
    }
    if spans.len() > from {
        let last = spans.last_mut().expect("non-empty");
        if start.t <= last.end.t {
            if end.t > last.end.t {
                last.end = end;
            }
            return;
        }
    }
    spans.push(Span { start, end });
}

/// The boundaries of one canonical list in order: start, end, start, end, ...
struct Events<'a> {
    spans: &'a [Span],
    next: usize,
}

impl Events<'_> {
    #[inline]
    fn peek(&self) -> Option<f32> {
        let span = self.spans.get(self.next / 2)?;
        Some(if self.next.is_multiple_of(2) {
            span.start.t
        } else {
            span.end.t
        })
    }

    #[inline]
    fn take(&mut self) -> Boundary {
        let span = &self.spans[self.next / 2];
        let b = if self.next.is_multiple_of(2) {
            span.start
        } else {
            span.end
        };
        self.next += 1;
        b
    }
}

/// Combine two canonical span lists by `op` into `out` (appended, canonical).
///
/// One sweep over the boundaries of both lists in order of t. Boundaries at
/// exactly the same t are applied together before the result is classified,
/// which is what makes coincident surfaces cancel instead of leaving
/// zero-width slivers. Where the result changes, the boundary of `a` is
/// reported if `a` changed there, else that of `b`; `b`'s surfaces are
/// flipped for a difference, since the result lies on their inner side.
pub fn combine(op: CsgOp, a: &[Span], b: &[Span], out: &mut Vec<Span>) {
    let mut ea = Events { spans: a, next: 0 };
    let mut eb = Events { spans: b, next: 0 };
    let (mut in_a, mut in_b, mut inside) = (false, false, false);
    let mut start = Boundary::new(0.0, 0);
    loop {
        let (ta, tb) = (ea.peek(), eb.peek());
        let t = match (ta, tb) {
            (None, None) => break,
            (Some(x), None) => x,
            (None, Some(y)) => y,
            (Some(x), Some(y)) => x.min(y),
        };
        let from_a = (ta == Some(t)).then(|| {
            in_a = !in_a;
            ea.take()
        });
        let from_b = (tb == Some(t)).then(|| {
            in_b = !in_b;
            eb.take()
        });
        let now = op.apply(in_a, in_b);
        if now == inside {
            continue;
        }
        let boundary = match (from_a, from_b) {
            (Some(ba), _) => ba,
            (None, Some(bb)) if op == CsgOp::Difference => bb.flipped(),
            (None, Some(bb)) => bb,
            (None, None) => unreachable!("t came from one of the lists"),
        };
        if now {
            start = boundary;
        } else {
            out.push(Span {
                start,
                end: boundary,
            });
        }
        inside = now;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spans(list: &[(f32, f32, u32)]) -> Vec<Span> {
        let mut out = Vec::new();
        for &(s, e, code) in list {
            push_span(&mut out, 0, Boundary::new(s, code), Boundary::new(e, code));
        }
        out
    }

    fn run(op: CsgOp, a: &[(f32, f32, u32)], b: &[(f32, f32, u32)]) -> Vec<(f32, u32, f32, u32)> {
        let mut out = Vec::new();
        combine(op, &spans(a), &spans(b), &mut out);
        out.iter()
            .map(|s| (s.start.t, s.start.code, s.end.t, s.end.code))
            .collect()
    }

    #[test]
    fn each_operator_on_two_overlapping_spans() {
        let a = [(0.0, 2.0, 1)];
        let b = [(1.0, 3.0, 2)];
        assert_eq!(run(CsgOp::Union, &a, &b), [(0.0, 1, 3.0, 2)]);
        assert_eq!(run(CsgOp::Intersection, &a, &b), [(1.0, 2, 2.0, 1)]);
        assert_eq!(run(CsgOp::Difference, &a, &b), [(0.0, 1, 1.0, 2 | FLIP)]);
        assert_eq!(run(CsgOp::Difference, &b, &a), [(2.0, 1 | FLIP, 3.0, 2)]);
    }

    #[test]
    fn a_hole_splits_a_span_and_both_new_walls_are_flipped() {
        let got = run(CsgOp::Difference, &[(0.0, 10.0, 1)], &[(4.0, 6.0, 2)]);
        assert_eq!(got, [(0.0, 1, 4.0, 2 | FLIP), (6.0, 2 | FLIP, 10.0, 1)]);
        // Subtracting twice flips twice: a − (b − c) keeps c's normal.
        let mut inner = Vec::new();
        combine(
            CsgOp::Difference,
            &spans(&[(2.0, 8.0, 2)]),
            &spans(&[(4.0, 6.0, 3)]),
            &mut inner,
        );
        let mut out = Vec::new();
        combine(
            CsgOp::Difference,
            &spans(&[(0.0, 10.0, 1)]),
            &inner,
            &mut out,
        );
        let codes: Vec<u32> = out
            .iter()
            .flat_map(|s| [s.start.code, s.end.code])
            .collect();
        assert_eq!(codes, [1, 2 | FLIP, 3, 3, 2 | FLIP, 1]);
    }

    #[test]
    fn identical_operands_cancel_exactly() {
        let a = [(1.5, 2.5, 1)];
        let b = [(1.5, 2.5, 2)];
        assert!(run(CsgOp::Difference, &a, &b).is_empty());
        assert_eq!(run(CsgOp::Intersection, &a, &b), [(1.5, 1, 2.5, 1)]);
        assert_eq!(run(CsgOp::Union, &a, &b), [(1.5, 1, 2.5, 1)]);
    }

    #[test]
    fn touching_spans_merge_with_no_boundary_between() {
        assert_eq!(
            run(CsgOp::Union, &[(0.0, 1.0, 1)], &[(1.0, 2.0, 2)]),
            [(0.0, 1, 2.0, 2)]
        );
        assert!(run(CsgOp::Intersection, &[(0.0, 1.0, 1)], &[(1.0, 2.0, 2)]).is_empty());
        assert_eq!(
            run(CsgOp::Difference, &[(0.0, 1.0, 1)], &[(1.0, 2.0, 2)]),
            [(0.0, 1, 1.0, 1)]
        );
    }

    #[test]
    fn empty_and_nan_spans_are_dropped_and_overlaps_merge() {
        let s = spans(&[(1.0, 1.0, 1), (f32::NAN, 2.0, 1), (0.0, f32::NAN, 1)]);
        assert!(s.is_empty());
        let s = spans(&[(0.0, 2.0, 1), (1.0, 3.0, 2), (3.0, 4.0, 3), (5.0, 6.0, 4)]);
        let got: Vec<(f32, f32)> = s.iter().map(|s| (s.start.t, s.end.t)).collect();
        assert_eq!(got, [(0.0, 4.0), (5.0, 6.0)]);
    }

    #[test]
    fn empty_operands() {
        let a = [(0.0, 1.0, 1), (2.0, 3.0, 1)];
        assert_eq!(run(CsgOp::Union, &a, &[]).len(), 2);
        assert_eq!(run(CsgOp::Union, &[], &a).len(), 2);
        assert!(run(CsgOp::Intersection, &a, &[]).is_empty());
        assert_eq!(run(CsgOp::Difference, &a, &[]).len(), 2);
        assert!(run(CsgOp::Difference, &[], &a).is_empty());
    }
}
