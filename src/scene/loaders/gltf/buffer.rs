//! Buffers: each resolved to exactly its `byteLength` bytes, from the GLB
//! BIN chunk, a base64 `data:` URI or a file beside the `.gltf` (its name
//! percent-decoded). A declared length is checked against the data actually
//! there before anything of that size is allocated, so a lying file cannot
//! make the loader reserve gigabytes.

use super::super::io_message;
use crate::error::{InputError, InputResult};
use ::gltf::json;
use std::borrow::Cow;
use std::io::Read;
use std::path::{Path, PathBuf};

/// Resolve every buffer to its bytes, exactly `byteLength` long.
pub(super) fn load_buffers<'a>(
    path: &Path,
    root: &json::Root,
    bin: Option<&'a [u8]>,
) -> InputResult<Vec<Cow<'a, [u8]>>> {
    let mut buffers = Vec::with_capacity(root.buffers.len());
    for (i, buffer) in root.buffers.iter().enumerate() {
        let at = |message: String| InputError::new(path, format!("buffers[{i}]"), message);
        let declared = buffer.byte_length.0;
        let data = match buffer.uri.as_deref() {
            None => {
                let bin = match (i, bin) {
                    (0, Some(bin)) => bin,
                    (0, None) => {
                        return Err(at(
                            "has no uri and the file has no GLB BIN chunk".to_string()
                        ))
                    }
                    _ => {
                        return Err(at("has no uri (only buffer 0 of a .glb file may \
                                       use the BIN chunk)"
                            .to_string()))
                    }
                };
                if declared > bin.len() as u64 {
                    return Err(at(format!(
                        "declares byteLength {declared} but the GLB BIN chunk has only {} bytes",
                        bin.len()
                    )));
                }
                Cow::Borrowed(&bin[..declared as usize])
            }
            Some(uri) if uri.starts_with("data:") => {
                Cow::Owned(decode_data_uri(uri, declared).map_err(at)?)
            }
            Some(uri) => Cow::Owned(read_buffer_file(path, uri, declared).map_err(at)?),
        };
        buffers.push(data);
    }
    Ok(buffers)
}

/// Decode a base64 `data:` URI holding at least `declared` bytes.
fn decode_data_uri(uri: &str, declared: u64) -> Result<Vec<u8>, String> {
    let Some((header, payload)) = uri.split_once(',') else {
        return Err("data: URI has no ',' before its data".to_string());
    };
    if !header.ends_with(";base64") {
        return Err("only base64 data: URIs are supported".to_string());
    }
    // Refuse before decoding if the text cannot possibly hold the bytes.
    let at_most = payload.len() as u64 / 4 * 3 + 3;
    if declared > at_most {
        return Err(format!(
            "declares byteLength {declared} but its data: URI holds at most {at_most} bytes"
        ));
    }
    let mut data = decode_base64(payload)?;
    if (data.len() as u64) < declared {
        return Err(format!(
            "declares byteLength {declared} but its data: URI holds only {} bytes",
            data.len()
        ));
    }
    data.truncate(declared as usize);
    Ok(data)
}

/// Standard (or URL-safe) base64, padding optional, whitespace ignored.
pub(super) fn decode_base64(text: &str) -> Result<Vec<u8>, String> {
    let mut out = Vec::with_capacity(text.len() / 4 * 3 + 3);
    let (mut bits, mut bit_count) = (0u32, 0u32);
    let mut padding = false;
    for c in text.bytes() {
        let value = match c {
            b'A'..=b'Z' => c - b'A',
            b'a'..=b'z' => c - b'a' + 26,
            b'0'..=b'9' => c - b'0' + 52,
            b'+' | b'-' => 62,
            b'/' | b'_' => 63,
            b'=' => {
                padding = true;
                continue;
            }
            b' ' | b'\t' | b'\r' | b'\n' => continue,
            other => {
                return Err(format!(
                    "data: URI contains '{}', which is not base64",
                    char::from(other).escape_default()
                ))
            }
        };
        if padding {
            return Err("data: URI has base64 data after '=' padding".to_string());
        }
        bits = (bits << 6) | u32::from(value);
        bit_count += 6;
        if bit_count >= 8 {
            bit_count -= 8;
            out.push((bits >> bit_count) as u8);
            bits &= (1 << bit_count) - 1;
        }
    }
    Ok(out)
}

/// The file a relative URI names, beside the glTF file (percent-decoded);
/// other schemes than `data:` (handled by the callers) are refused.
pub(super) fn uri_file(gltf_path: &Path, uri: &str) -> Result<PathBuf, String> {
    let scheme_end = uri.find(':');
    let slash = uri.find('/').unwrap_or(uri.len());
    if let Some(colon) = scheme_end.filter(|&c| c < slash && c > 1) {
        return Err(format!(
            "uri scheme '{}:' is not supported; use a relative file path or a data: URI",
            &uri[..colon]
        ));
    }
    let name = percent_decode(uri)?;
    Ok(gltf_path.parent().unwrap_or(Path::new("")).join(name))
}

/// Read `declared` bytes of a buffer file named by a relative URI.
fn read_buffer_file(gltf_path: &Path, uri: &str, declared: u64) -> Result<Vec<u8>, String> {
    let file = uri_file(gltf_path, uri)?;
    let cannot = |e: std::io::Error| format!("cannot read {}: {}", file.display(), io_message(&e));
    let size = std::fs::metadata(&file).map_err(cannot)?.len();
    if size < declared {
        return Err(format!(
            "declares byteLength {declared} but {} has only {size} bytes",
            file.display()
        ));
    }
    let mut data = Vec::with_capacity(declared as usize);
    std::fs::File::open(&file)
        .map_err(cannot)?
        .take(declared)
        .read_to_end(&mut data)
        .map_err(cannot)?;
    if (data.len() as u64) < declared {
        return Err(format!(
            "declares byteLength {declared} but only {} bytes could be read from {}",
            data.len(),
            file.display()
        ));
    }
    Ok(data)
}

fn percent_decode(uri: &str) -> Result<String, String> {
    let bytes = uri.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] == b'%' {
            let hex = uri
                .get(i + 1..i + 3)
                .and_then(|h| u8::from_str_radix(h, 16).ok())
                .ok_or_else(|| format!("uri '{uri}' has a malformed %-escape"))?;
            out.push(hex);
            i += 3;
        } else {
            out.push(bytes[i]);
            i += 1;
        }
    }
    String::from_utf8(out).map_err(|_| format!("uri '{uri}' does not decode to UTF-8"))
}

#[cfg(test)]
mod tests {
    use super::super::test_support::*;
    use super::*;

    #[test]
    fn bin_file_data_uri_and_glb_load_the_same() {
        let b = triangle_builder();
        let rest = format!(r#"{TRIANGLE_MESH},"nodes":[{{"mesh":0,"translation":[0,0,-1]}}]"#);
        let dir = temp_dir("same");
        let from_bin = load_gltf(&b.write_gltf(&dir, "separate", &rest)).unwrap();
        let embedded = b.json(Some(&b.data_uri()), &rest);
        let from_uri = load_gltf(&write(&dir, "embedded.gltf", embedded.as_bytes())).unwrap();
        let from_glb = load_gltf(&write(&dir, "binary.glb", &b.glb(&rest))).unwrap();
        assert_eq!(from_bin, from_uri);
        assert_eq!(from_bin, from_glb);
        assert_corners(
            &from_glb.meshes[0],
            [[0., 0., -1.], [1., 0., -1.], [0., 1., -1.]],
        );
        // A percent-encoded file name resolves too.
        write(&dir, "with space.bin", &b.bin);
        let json = b.json(Some("with%20space.bin"), &rest);
        let spaced = load_gltf(&write(&dir, "spaced.gltf", json.as_bytes())).unwrap();
        assert_eq!(spaced, from_bin);
    }

    #[test]
    fn buffers_shorter_than_declared_are_refused() {
        let b = triangle_builder();
        let rest = format!(r#"{TRIANGLE_MESH},"nodes":[{{"mesh":0}}]"#);
        let dir = temp_dir("short");
        // External file shorter than byteLength.
        let path = b.write_gltf(&dir, "short", &rest);
        write(&dir, "short.bin", &b.bin[..10]);
        expect_error(
            load_gltf(&path),
            "short.gltf",
            "buffers[0]",
            "has only 10 bytes",
        );
        // A huge declared length is refused without trying to allocate it.
        let json = b.json(Some("short.bin"), &rest).replacen(
            &format!("\"byteLength\":{}", b.bin.len()),
            "\"byteLength\":1000000000000000",
            1,
        );
        let path = write(&dir, "huge.gltf", json.as_bytes());
        expect_error(
            load_gltf(&path),
            "huge.gltf",
            "buffers[0]",
            "byteLength 1000000000000000",
        );
        // data: URI shorter than byteLength.
        let json = b.json(Some(&b.data_uri()), &rest).replacen(
            &format!("\"byteLength\":{}", b.bin.len()),
            "\"byteLength\":1000000000000",
            1,
        );
        let path = write(&dir, "uri.gltf", json.as_bytes());
        expect_error(
            load_gltf(&path),
            "uri.gltf",
            "buffers[0]",
            "data: URI holds at most",
        );
        // GLB whose BIN chunk is shorter than the buffer's byteLength.
        let json = b.json(None, &rest).replacen(
            &format!("\"byteLength\":{}", b.bin.len()),
            "\"byteLength\":4096",
            1,
        );
        let path = write(&dir, "short.glb", &glb_bytes(json.as_bytes(), Some(&b.bin)));
        expect_error(
            load_gltf(&path),
            "short.glb",
            "buffers[0]",
            "BIN chunk has only",
        );
        // GLB without a BIN chunk at all.
        let path = write(
            &dir,
            "nobin.glb",
            &glb_bytes(b.json(None, &rest).as_bytes(), None),
        );
        expect_error(
            load_gltf(&path),
            "nobin.glb",
            "buffers[0]",
            "no GLB BIN chunk",
        );
    }

    #[test]
    fn missing_buffer_file_is_named() {
        let b = triangle_builder();
        let rest = format!(r#"{TRIANGLE_MESH},"nodes":[{{"mesh":0}}]"#);
        let dir = temp_dir("missing");
        let path = write(
            &dir,
            "lonely.gltf",
            b.json(Some("gone.bin"), &rest).as_bytes(),
        );
        expect_error(
            load_gltf(&path),
            "lonely.gltf",
            "buffers[0]",
            "gone.bin: No such file or directory",
        );
        let path = write(
            &dir,
            "web.gltf",
            b.json(Some("https://example.com/x.bin"), &rest).as_bytes(),
        );
        expect_error(
            load_gltf(&path),
            "web.gltf",
            "buffers[0]",
            "scheme 'https:'",
        );
    }

    #[test]
    fn base64_round_trips() {
        for len in 0..20 {
            let data: Vec<u8> = (0..len).map(|i| (i * 37 + 11) as u8).collect();
            assert_eq!(decode_base64(&encode_base64(&data)).unwrap(), data);
        }
        assert!(decode_base64("ab!c").is_err());
    }
}
