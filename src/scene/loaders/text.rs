//! Text files (OBJ, MTL, OFF, ASCII STL) as other tools read them: UTF-8 (a leading byte-order mark
//! dropped), UTF-16 with a byte-order mark, and otherwise Latin-1.
//!
//! OBJ and MTL files come from many exporters: Windows tools write UTF-16
//! with a byte-order mark, and older ones Latin-1 (ISO 8859-1) bytes in
//! comments and material names. Latin-1 maps every byte to the code point
//! of the same value, so any byte string decodes; a NUL byte, which no text
//! file holds, is refused instead, so a binary file is still told apart.
//! Valid UTF-8 (nearly every file) is borrowed as it is: the only cost is
//! the UTF-8 check the loader made anyway.

use crate::error::{InputError, InputResult};
use std::borrow::Cow;
use std::path::Path;

/// The bytes of a text file as text: see the module documentation. An
/// error names the line of the first NUL byte of a file that is neither
/// UTF-8 nor UTF-16.
pub(crate) fn decode_text<'a>(path: &Path, bytes: &'a [u8]) -> InputResult<Cow<'a, str>> {
    if let Ok(text) = std::str::from_utf8(bytes) {
        return Ok(Cow::Borrowed(text.strip_prefix('\u{feff}').unwrap_or(text)));
    }
    let utf16 = match bytes {
        [0xff, 0xfe, rest @ ..] => Some((rest, u16::from_le_bytes as fn([u8; 2]) -> u16)),
        [0xfe, 0xff, rest @ ..] => Some((rest, u16::from_be_bytes as fn([u8; 2]) -> u16)),
        _ => None,
    };
    if let Some((rest, unit)) = utf16 {
        let units = rest.chunks_exact(2).map(|p| unit([p[0], p[1]]));
        // An unpaired surrogate (a broken file) becomes U+FFFD: it can only
        // stand in a comment or a name, which the loaders then report.
        let text: String = char::decode_utf16(units)
            .map(|c| c.unwrap_or(char::REPLACEMENT_CHARACTER))
            .collect();
        return Ok(Cow::Owned(text));
    }
    if let Some(at) = bytes.iter().position(|&b| b == 0) {
        let line = bytes[..at].iter().filter(|&&b| b == b'\n').count() + 1;
        return Err(InputError::new(
            path,
            format!("line {line}"),
            "not a text file (it holds a NUL byte), so not the text format its name says",
        ));
    }
    Ok(Cow::Owned(bytes.iter().map(|&b| char::from(b)).collect()))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn decode(bytes: &[u8]) -> InputResult<String> {
        decode_text(Path::new("t.obj"), bytes).map(Cow::into_owned)
    }

    fn utf16(text: &str, big_endian: bool) -> Vec<u8> {
        let mut out = if big_endian {
            vec![0xfe, 0xff]
        } else {
            vec![0xff, 0xfe]
        };
        for unit in text.encode_utf16() {
            out.extend(if big_endian {
                unit.to_be_bytes()
            } else {
                unit.to_le_bytes()
            });
        }
        out
    }

    #[test]
    fn utf8_is_borrowed_and_its_byte_order_mark_dropped() {
        let text = "v 1 2 3\n# café\n";
        assert!(matches!(
            decode_text(Path::new("t.obj"), text.as_bytes()).unwrap(),
            Cow::Borrowed(t) if t == text
        ));
        let mut marked = "\u{feff}".as_bytes().to_vec();
        marked.extend_from_slice(text.as_bytes());
        assert_eq!(decode(&marked).unwrap(), text);
    }

    #[test]
    fn utf16_with_a_byte_order_mark_either_way_round() {
        let text = "v 1 2 3\r\nnewmtl grün\r\n";
        assert_eq!(decode(&utf16(text, false)).unwrap(), text);
        assert_eq!(decode(&utf16(text, true)).unwrap(), text);
        // An odd trailing byte and an unpaired surrogate do not panic.
        let mut odd = utf16("v 1", true);
        odd.extend([0xd8, 0x00, b'\n']);
        assert_eq!(decode(&odd).unwrap(), "v 1\u{fffd}");
    }

    #[test]
    fn other_bytes_are_latin1_but_a_nul_byte_is_refused() {
        // "# caf\xe9" is Latin-1 for "# café", and not UTF-8.
        assert_eq!(
            decode(b"# caf\xe9\nv 0 0 0\n").unwrap(),
            "# café\nv 0 0 0\n"
        );
        let err = decode(b"v 0 0 0\n\xff\x00\n").unwrap_err();
        assert_eq!(err.location, "line 2");
        assert!(err.message.contains("NUL"), "{err}");
        // Valid UTF-8 with a NUL byte is still text, as it always was.
        assert_eq!(decode(b"a\x00").unwrap(), "a\0");
    }
}
