//! The bytes of a glTF file: the GLB container's chunks, buffers from the file, `data:` URIs
//! or external files, all checked before use.

use super::{Ctx, ErrorKind, SceneError};
use std::borrow::Cow;
use std::path::Path;

pub(super) fn u32_at(bytes: &[u8], at: usize) -> Option<u32> {
    let b = bytes.get(at..at.checked_add(4)?)?;
    Some(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
}

/// Splits a .glb into its JSON chunk and optional BIN chunk. Done here rather than by the
/// gltf crate because its GLB reader subtracts from the header length unchecked (a
/// malformed header would panic in debug builds) and its errors do not say which part is bad.
pub(super) fn split_glb<'b>(ctx: Ctx, bytes: &'b [u8]) -> Result<(&'b [u8], Option<&'b [u8]>), SceneError> {
    let bad =
        |problem: String| ctx.fail(ErrorKind::Parse, "GLB container", problem, "re-export the .glb; the file is damaged or truncated");
    let version = u32_at(bytes, 4).ok_or_else(|| bad(format!("the header needs 12 bytes, the file has {}", bytes.len())))?;
    let length = u32_at(bytes, 8).ok_or_else(|| bad(format!("the header needs 12 bytes, the file has {}", bytes.len())))? as usize;
    if version != 2 {
        return Err(ctx.fail(
            ErrorKind::Unsupported,
            "GLB container",
            format!("version {version}"),
            "relume reads glTF 2.0; convert the file",
        ));
    }
    if length > bytes.len() || length < 12 {
        return Err(bad(format!("the header says {length} bytes, the file has {}", bytes.len())));
    }
    let bytes = &bytes[..length];
    // (chunk type, chunk data, offset of the next chunk)
    type Chunk<'c> = Option<(u32, &'c [u8], usize)>;
    let chunk = |at: usize, name: &str| -> Result<Chunk<'b>, SceneError> {
        if at >= bytes.len() {
            return Ok(None);
        }
        let (Some(len), Some(ty)) = (u32_at(bytes, at), u32_at(bytes, at + 4)) else {
            return Err(bad(format!("the {name} chunk header is cut off at byte {at}")));
        };
        let start = at + 8;
        let end = start.checked_add(len as usize).filter(|&e| e <= bytes.len());
        let Some(end) = end else {
            return Err(bad(format!("the {name} chunk says {len} bytes, only {} follow", bytes.len() - start)));
        };
        Ok(Some((ty, &bytes[start..end], end)))
    };
    const JSON: u32 = 0x4E4F_534A;
    const BIN: u32 = 0x004E_4942;
    let Some((ty, json, next)) = chunk(12, "JSON")? else {
        return Err(bad("there is no JSON chunk".into()));
    };
    if ty != JSON {
        return Err(bad(format!("the first chunk has type 0x{ty:08x}, not JSON")));
    }
    let bin = match chunk(next, "BIN")? {
        Some((BIN, data, _)) => Some(data),
        // Unknown chunks after the JSON chunk must be ignored (glTF 2.0 §4.4.3.3).
        _ => None,
    };
    Ok((json, bin))
}

pub(super) fn load_buffers<'b>(ctx: Ctx, document: &gltf::Document, blob: Option<&'b [u8]>) -> Result<Vec<Cow<'b, [u8]>>, SceneError> {
    let mut out = Vec::with_capacity(document.buffers().len());
    for buffer in document.buffers() {
        let (data, label): (Cow<[u8]>, String) = match buffer.source() {
            gltf::buffer::Source::Bin => match blob {
                Some(b) if buffer.index() == 0 => (Cow::Borrowed(b), "the GLB BIN chunk".to_string()),
                _ => {
                    return Err(ctx.fail(
                        ErrorKind::Buffer,
                        format!("buffer {}", buffer.index()),
                        "has no uri and there is no GLB BIN chunk for it",
                        "give the buffer a uri (a .bin file next to the .gltf), or save the scene as .glb",
                    ))
                }
            },
            gltf::buffer::Source::Uri(uri) => {
                let item = format!("buffer {} (\"{}\")", buffer.index(), short_uri(uri));
                (Cow::Owned(read_uri(ctx, &item, uri)?), format!("\"{}\"", short_uri(uri)))
            }
        };
        if data.len() < buffer.length() {
            return Err(ctx.fail(
                ErrorKind::Buffer,
                format!("buffer {}", buffer.index()),
                format!("{label} has {} bytes but the buffer's byteLength is {}", data.len(), buffer.length()),
                "the data is truncated: re-export the scene (or regenerate it), or fix byteLength",
            ));
        }
        out.push(data);
    }
    Ok(out)
}

/// A URI for messages: data: URIs are cut short, they can be megabytes long.
pub(super) fn short_uri(uri: &str) -> String {
    if uri.starts_with("data:") {
        let head: String = uri.chars().take(40).collect();
        format!("{head}…")
    } else {
        uri.to_string()
    }
}

/// Reads a buffer or image URI: a `data:` URI (base64 or percent-encoded), or a relative
/// path resolved against the scene file's folder (percent-decoded, as glTF URIs are).
pub(super) fn read_uri(ctx: Ctx, item: &str, uri: &str) -> Result<Vec<u8>, SceneError> {
    if let Some(rest) = uri.strip_prefix("data:") {
        let Some((header, payload)) = rest.split_once(',') else {
            return Err(ctx.fail(
                ErrorKind::Buffer,
                item,
                "the data: URI has no ',' before its payload",
                "write it as data:<type>;base64,<data>",
            ));
        };
        return if header.ends_with(";base64") {
            decode_base64(payload).map_err(|at| {
                ctx.fail(
                    ErrorKind::Buffer,
                    item,
                    format!("the data: URI is not valid base64 (at character {at})"),
                    "re-encode the data as standard base64",
                )
            })
        } else {
            Ok(percent_decode(payload))
        };
    }
    if uri.contains("://") {
        return Err(ctx.fail(
            ErrorKind::Unsupported,
            item,
            format!("the uri \"{uri}\" is not a local file"),
            "download the file and refer to it by a relative path",
        ));
    }
    let decoded = percent_decode(uri);
    let relative = String::from_utf8_lossy(&decoded).into_owned();
    refuse_outside(ctx, item, &relative)?;
    let file = ctx.path.parent().unwrap_or(Path::new("")).join(&relative);
    crate::inputs::admit(&file).map_err(|e| ctx.fail(ErrorKind::Io, item, format!("{} {e}", file.display()), "point the uri at a file"))?;
    std::fs::read(&file).map_err(|e| {
        if e.kind() == std::io::ErrorKind::NotFound {
            ctx.fail(ErrorKind::NotFound, item, format!("{} not found", file.display()), "put the file next to the .gltf, or fix the uri")
        } else {
            ctx.fail(ErrorKind::Io, item, format!("cannot read {}: {e}", file.display()), "check the file's permissions")
        }
    })
}

/// Refuses a file path of the scene's that leaves its folder (absolute, or up through `..`
/// past it), unless the load allows outside files: a downloaded scene must not read
/// `/etc/passwd` or `../../secrets` as a buffer.
pub(super) fn refuse_outside(ctx: Ctx, item: &str, relative: &str) -> Result<(), SceneError> {
    use std::path::Component;
    let mut depth = 0i32;
    let leaves = Path::new(relative).components().any(|c| {
        depth += match c {
            Component::ParentDir => -1,
            Component::Normal(_) => 1,
            Component::CurDir => 0,
            Component::RootDir | Component::Prefix(_) => return true,
        };
        depth < 0
    });
    if leaves && !ctx.outside_files {
        return Err(ctx.fail(
            ErrorKind::Unsupported,
            item,
            format!("\"{relative}\" lies outside the scene's folder"),
            "put the file beside the scene, or pass --allow-outside-files if you trust the scene",
        ));
    }
    Ok(())
}

pub(super) fn percent_decode(s: &str) -> Vec<u8> {
    let bytes = s.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        let hex = |b: u8| (b as char).to_digit(16);
        if bytes[i] == b'%' && i + 2 < bytes.len() {
            if let (Some(h), Some(l)) = (hex(bytes[i + 1]), hex(bytes[i + 2])) {
                out.push((h * 16 + l) as u8);
                i += 3;
                continue;
            }
        }
        out.push(bytes[i]);
        i += 1;
    }
    out
}

/// Standard base64 (RFC 4648 §4), padding optional. Written here to avoid a dependency
/// for twenty lines; the error is the offset of the first bad character.
pub(super) fn decode_base64(text: &str) -> Result<Vec<u8>, usize> {
    let value = |c: u8| -> Option<u32> {
        Some(match c {
            b'A'..=b'Z' => c - b'A',
            b'a'..=b'z' => c - b'a' + 26,
            b'0'..=b'9' => c - b'0' + 52,
            b'+' => 62,
            b'/' => 63,
            _ => return None,
        } as u32)
    };
    let body = text.trim_end_matches('=');
    if text.len() - body.len() > 2 {
        return Err(body.len());
    }
    let mut out = Vec::with_capacity(body.len() * 3 / 4);
    let (mut acc, mut bits) = (0u32, 0u32);
    for (at, c) in body.bytes().enumerate() {
        acc = (acc << 6) | value(c).ok_or(at)?;
        bits += 6;
        if bits >= 8 {
            bits -= 8;
            out.push((acc >> bits) as u8);
            acc &= (1 << bits) - 1;
        }
    }
    if bits >= 6 {
        // One leftover character cannot encode a byte.
        return Err(body.len());
    }
    Ok(out)
}
#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;
    #[test]
    fn base64_round_trips_known_values() {
        assert_eq!(decode_base64("aGVsbG8=").unwrap(), b"hello");
        assert_eq!(decode_base64("aGVsbG8").unwrap(), b"hello");
        assert_eq!(decode_base64("AAECAwQ=").unwrap(), [0, 1, 2, 3, 4]);
        assert!(decode_base64("aGV*bG8=").is_err());
        assert!(decode_base64("a").is_err());
    }

    #[test]
    fn percent_decoding() {
        assert_eq!(percent_decode("my%20scene.bin"), b"my scene.bin");
        assert_eq!(percent_decode("100%"), b"100%");
        assert_eq!(percent_decode("a%2"), b"a%2");
    }

    #[test]
    fn glb_splitter_refuses_damaged_headers_without_panicking() {
        let ctx = Ctx { path: Path::new("x.glb"), outside_files: false, max_texture_pixels: 1 };
        for bytes in
            [&b"glTF"[..], b"glTF\x02\0\0\0\x04\0\0\0", b"glTF\x02\0\0\0\xff\xff\xff\xff", b"glTF\x02\0\0\0\x20\0\0\0\xff\xff\0\0JSON"]
        {
            assert!(split_glb(ctx, bytes).is_err());
        }
    }
}
