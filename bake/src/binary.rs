//! Little-endian binary files of the bake artifact: a writer of u32 and f32 values, and a
//! reader that refuses to read past the end (naming the file, what it was reading and where),
//! so a count read from a file never allocates more than the file holds.

use crate::artifact::{fail, ArtifactError, REBAKE};
use std::path::Path;

/// Appends little-endian values.
pub struct Writer {
    pub bytes: Vec<u8>,
}

impl Writer {
    pub fn new(magic: &[u8; 8]) -> Writer {
        Writer { bytes: magic.to_vec() }
    }

    pub fn u32s(&mut self, values: &[u32]) {
        self.bytes.extend(values.iter().flat_map(|v| v.to_le_bytes()));
    }

    pub fn f32s(&mut self, values: &[f32]) {
        self.bytes.extend(values.iter().flat_map(|v| v.to_le_bytes()));
    }
}

/// Reads little-endian values from one file's bytes.
pub struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
    path: &'a Path,
}

impl<'a> Reader<'a> {
    /// A reader of `bytes` (the file at `path`), after checking its magic number.
    pub fn new(bytes: &'a [u8], path: &'a Path, magic: &[u8; 8], what: &str) -> Result<Reader<'a>, ArtifactError> {
        let mut reader = Reader { bytes, at: 0, path };
        if reader.take(8, "the magic number")? != magic {
            return Err(fail(path, format!("not a relume {what} file (wrong magic number)"), REBAKE));
        }
        Ok(reader)
    }

    pub fn path(&self) -> &Path {
        self.path
    }

    pub fn take(&mut self, n: usize, what: &str) -> Result<&'a [u8], ArtifactError> {
        let end = self.at.checked_add(n).filter(|&end| end <= self.bytes.len());
        let Some(end) = end else {
            return Err(fail(
                self.path,
                format!("truncated: {what} needs {n} bytes at offset {} but the file has {}", self.at, self.bytes.len()),
                REBAKE,
            ));
        };
        let slice = &self.bytes[self.at..end];
        self.at = end;
        Ok(slice)
    }

    pub fn u32(&mut self, what: &str) -> Result<u32, ArtifactError> {
        Ok(u32::from_le_bytes(self.take(4, what)?.try_into().expect("4 bytes")))
    }

    pub fn u32s(&mut self, count: usize, what: &str) -> Result<Vec<u32>, ArtifactError> {
        let bytes = self.take(count.saturating_mul(4), what)?;
        Ok(bytes.chunks_exact(4).map(|c| u32::from_le_bytes(c.try_into().expect("4 bytes"))).collect())
    }

    pub fn f32s(&mut self, count: usize, what: &str) -> Result<Vec<f32>, ArtifactError> {
        let bytes = self.take(count.saturating_mul(4), what)?;
        Ok(bytes.chunks_exact(4).map(|c| f32::from_le_bytes(c.try_into().expect("4 bytes"))).collect())
    }

    /// Refuses bytes left after the last value.
    pub fn finish(self, after: &str) -> Result<(), ArtifactError> {
        match self.bytes.len() - self.at {
            0 => Ok(()),
            left => Err(fail(self.path, format!("{left} bytes after {after}"), REBAKE)),
        }
    }
}
