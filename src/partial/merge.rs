//! Merging partial renders (`strata merge`).
//!
//! Parts must come from the same render (same strata version, scene
//! fingerprint and settings, and the same P), each must be complete (not an
//! unfinished checkpoint), and their slices must not overlap or leave gaps.
//! The sums are fixed point, so the merged film does not depend on the order
//! of the parts and equals the film of one process rendering every slice.

use super::format::Partial;
use crate::error::{InputError, InputResult};
use std::path::PathBuf;

/// Slices `range` of `count` as text: `2/5`, `2-3/5`.
fn slices_text(range: std::ops::Range<u32>, count: u32) -> String {
    if range.len() == 1 {
        format!("{}/{count}", range.start)
    } else {
        format!("{}-{}/{count}", range.start, range.end - 1)
    }
}

/// What a merge accepts.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct MergeRules {
    /// Every slice 0..P must be there (for an image; a merged `.strata`
    /// may hold any contiguous run of them).
    pub require_all: bool,
    /// A preview: unfinished checkpoints and missing slices are welcome,
    /// and each pixel is the mean of whatever samples the parts hold.
    pub preview: bool,
    /// Parts written by different builds of strata may mix.
    pub force: bool,
}

/// Sum `parts` (path, contents) into one partial covering a contiguous run
/// of slices, under `rules`. Errors name the offending file.
pub fn merge_partials(
    mut parts: Vec<(PathBuf, Partial)>,
    rules: MergeRules,
) -> InputResult<Partial> {
    if parts.is_empty() {
        return Err(InputError::file("<command line>", "no parts to merge"));
    }
    if rules.preview {
        return merge_preview(parts, rules.force);
    }
    for (path, p) in &parts {
        let h = &p.header;
        if !h.is_complete() {
            let full = h.slice_samples();
            return Err(InputError::file(
                path,
                format!(
                    "an unfinished checkpoint: holds samples {}..{} of slice {}'s {}..{}; finish it with --resume, or preview it with merge --partial",
                    h.samples.start, h.samples.end, h.slices_text(), full.start, full.end
                ),
            ));
        }
    }
    check_same_render(&parts, rules.force)?;
    parts.sort_by_key(|(_, p)| p.header.slices.start);
    let count = parts[0].1.header.slice_count;
    for pair in parts.windows(2) {
        let (prev_path, prev) = (&pair[0].0, &pair[0].1.header);
        let (path, next) = (&pair[1].0, &pair[1].1.header);
        if next.slices.start < prev.slices.end {
            let overlap = next.slices.start..prev.slices.end.min(next.slices.end);
            return Err(InputError::file(
                path,
                format!(
                    "duplicate slice {}: also in {}",
                    slices_text(overlap, count),
                    prev_path.display()
                ),
            ));
        }
        if next.slices.start > prev.slices.end {
            return Err(InputError::file(
                path,
                format!(
                    "missing slice {} between {} and this part",
                    slices_text(prev.slices.end..next.slices.start, count),
                    prev_path.display()
                ),
            ));
        }
    }
    if rules.require_all {
        let (lo_path, lo) = (&parts[0].0, &parts[0].1.header);
        let (hi_path, hi) = (&parts[parts.len() - 1].0, &parts[parts.len() - 1].1.header);
        if lo.slices.start > 0 {
            return Err(InputError::file(
                lo_path,
                format!(
                    "missing slice {} before this part",
                    slices_text(0..lo.slices.start, count)
                ),
            ));
        }
        if hi.slices.end < count {
            return Err(InputError::file(
                hi_path,
                format!(
                    "missing slice {} after this part",
                    slices_text(hi.slices.end..count, count)
                ),
            ));
        }
    }
    let mut iter = parts.into_iter();
    let (_, mut merged) = iter.next().expect("at least one part");
    for (_, p) in iter {
        merged.film.merge(&p.film);
        merged.header.slices.end = p.header.slices.end;
    }
    merged.header.samples = merged.header.slice_samples();
    Ok(merged)
}

/// Every part describes the same render as the first (and, unless
/// `force`, was written by the same build).
fn check_same_render(parts: &[(PathBuf, Partial)], force: bool) -> InputResult<()> {
    let (first_path, first) = (&parts[0].0, &parts[0].1.header);
    for (path, p) in &parts[1..] {
        let h = &p.header;
        let mismatch = h
            .render_mismatch(first)
            .map(|m| format!("{m} (this file vs that one)"))
            .or_else(|| {
                // Not the film but how an image shows it: one image, one
                // curve and one exposure (an EXR shows neither: the
                // command line gives its parts the first's).
                (h.tonemap != first.tonemap).then(|| {
                    format!(
                        "tone curve: {} vs {} (this file vs that one); choose one with strata merge --tonemap",
                        h.tonemap, first.tonemap
                    )
                })
            })
            .or_else(|| {
                (h.exposure.to_bits() != first.exposure.to_bits()).then(|| {
                    format!(
                        "exposure: {} vs {} stops (this file vs that one); choose one with strata merge --exposure",
                        h.exposure, first.exposure
                    )
                })
            })
            .or_else(|| h.build_mismatch(first).filter(|_| !force));
        if let Some(m) = mismatch {
            return Err(InputError::file(
                path,
                format!(
                    "not part of the same render as {}: {m}",
                    first_path.display()
                ),
            ));
        }
    }
    Ok(())
}

/// A preview of whatever the parts hold: no slice may be in two parts, but
/// slices may be missing and checkpoints unfinished.
fn merge_preview(mut parts: Vec<(PathBuf, Partial)>, force: bool) -> InputResult<Partial> {
    check_same_render(&parts, force)?;
    parts.sort_by_key(|(_, p)| p.header.slices.start);
    for pair in parts.windows(2) {
        if pair[1].1.header.slices.start < pair[0].1.header.slices.end {
            return Err(InputError::file(
                &pair[1].0,
                format!("holds a slice that {} holds too", pair[0].0.display()),
            ));
        }
    }
    let mut iter = parts.into_iter();
    let (_, mut merged) = iter.next().expect("at least one part");
    for (_, p) in iter {
        merged.film.merge(&p.film);
    }
    Ok(merged)
}
