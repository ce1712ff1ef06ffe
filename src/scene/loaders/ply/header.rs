//! PLY headers as other tools read them: before the first `element`, a
//! line that starts with no header keyword is a comment without the word
//! `comment` (old Blender exports write `Created by Blender3D 247 - ...`
//! there), skipped with a warning. The header parser (`ply-rs-bw`) would
//! refuse the whole file.
//!
//! Only those lines are looked at, so a valid file costs a scan of its
//! first few header lines and no copy; a file with such a line is copied
//! once, the line made a `comment`, which keeps every line number.

use crate::error::InputError;
use std::path::Path;

/// The words a PLY header line may start with.
const KEYWORDS: &[&[u8]] = &[
    b"ply",
    b"format",
    b"comment",
    b"obj_info",
    b"element",
    b"property",
    b"end_header",
];

/// The file's bytes with every stray line before the first `element` made
/// a bare `comment`, or `None` where it has none; a warning naming the file
/// and line for each.
pub(super) fn without_stray_lines(
    path: &Path,
    bytes: &[u8],
    warnings: &mut Vec<InputError>,
) -> Option<Vec<u8>> {
    if !bytes.starts_with(b"ply") {
        return None; // not a PLY file: the parser says so
    }
    // (start, end) of each stray line, without its line ending.
    let mut stray = Vec::new();
    let mut start = 0;
    let mut number = 0;
    while start < bytes.len() {
        number += 1;
        let end = bytes[start..]
            .iter()
            .position(|&b| b == b'\n')
            .map_or(bytes.len(), |i| start + i);
        let line = bytes[start..end]
            .strip_suffix(b"\r")
            .unwrap_or(&bytes[start..end]);
        let word = line
            .split(|b| b.is_ascii_whitespace())
            .find(|w| !w.is_empty())
            .unwrap_or(b"");
        if word == b"element" || word == b"end_header" {
            break;
        }
        if !word.is_empty() && !KEYWORDS.contains(&word) {
            let text = String::from_utf8_lossy(line);
            warnings.push(InputError::new(
                path,
                format!("line {number}"),
                format!(
                    "'{}' is not a PLY header line (no keyword such as comment or element); \
                     skipped as a comment",
                    text.trim()
                ),
            ));
            stray.push((start, start + line.len()));
        }
        start = end + 1;
    }
    if stray.is_empty() {
        return None;
    }
    let mut fixed = Vec::with_capacity(bytes.len());
    let mut copied = 0;
    for (from, to) in stray {
        fixed.extend_from_slice(&bytes[copied..from]);
        fixed.extend_from_slice(b"comment");
        copied = to;
    }
    fixed.extend_from_slice(&bytes[copied..]);
    Some(fixed)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fix(bytes: &[u8]) -> (Option<Vec<u8>>, Vec<InputError>) {
        let mut warnings = Vec::new();
        let fixed = without_stray_lines(Path::new("w.ply"), bytes, &mut warnings);
        (fixed, warnings)
    }

    #[test]
    fn a_bare_line_before_element_becomes_a_comment_keeping_line_numbers() {
        let header = b"ply\r\nformat ascii 1.0\r\nCreated by Blender3D 247\r\n\
                       element vertex 0\r\nend_header\r\n";
        let (fixed, warnings) = fix(header);
        let fixed = fixed.expect("a stray line");
        assert_eq!(
            fixed,
            b"ply\r\nformat ascii 1.0\r\ncomment\r\nelement vertex 0\r\nend_header\r\n"
        );
        assert_eq!(warnings.len(), 1);
        assert_eq!(warnings[0].location, "line 3");
        assert!(warnings[0].message.contains("Created by Blender3D 247"));
    }

    #[test]
    fn valid_headers_and_lines_after_element_are_left_alone() {
        let valid = b"ply\nformat binary_little_endian 1.0\ncomment x\nobj_info y\n\
                      element vertex 1\nproprety float x\nend_header\n\xff\xfe";
        assert_eq!(fix(valid), (None, Vec::new()));
        assert_eq!(fix(b"not a ply file\nhello\n"), (None, Vec::new()));
        assert_eq!(fix(b"ply"), (None, Vec::new()));
    }
}
