//! The one place where binary encoding happens.
//!
//! Every binary file of the project (meshes here, multiresolution pyramids in the
//! subdivision crates) goes through [`encode`] and [`decode`]: a 8-byte magic number
//! naming the payload, a little-endian `u32` format version, then the payload encoded
//! with `bincode` 2 (standard configuration) through its serde support. Swapping the
//! encoder means changing this module only.
//!
//! A truncated, corrupted or foreign file is an error, never a panic, and decoding never
//! reserves more memory than the input can fill, so a corrupted length prefix cannot
//! exhaust memory.

use bincode::error::DecodeError;
use serde::Serialize;
use serde::de::DeserializeOwned;
use thiserror::Error;

use crate::mesh::HalfedgeMesh;
use crate::soup::PolygonSoup;

/// Magic number of a binary mesh file.
pub const MESH_MAGIC: [u8; 8] = *b"MRSMESH\0";
/// Current version of the binary mesh format.
pub const MESH_VERSION: u32 = 1;

/// Why a binary payload could not be read or written.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum BinaryError {
    /// The data is shorter than the 12-byte header.
    #[error("truncated header: {len} bytes, need at least 12")]
    TruncatedHeader {
        /// Bytes available.
        len: usize,
    },
    /// The magic number names another kind of file.
    #[error("not a {expected} file (magic number {found:?})")]
    WrongMagic {
        /// What was expected, in words.
        expected: String,
        /// The 8 bytes found.
        found: [u8; 8],
    },
    /// The file was written by another version of the format.
    #[error("unsupported format version {found} (this build reads version {supported})")]
    UnsupportedVersion {
        /// Version in the file.
        found: u32,
        /// Version this build reads.
        supported: u32,
    },
    /// The payload could not be decoded (truncated or corrupted).
    #[error("corrupted or truncated payload at byte {offset}: {message}")]
    Corrupted {
        /// Byte offset in the file where decoding stopped (after the header).
        offset: usize,
        /// What the decoder reported.
        message: String,
    },
    /// Bytes were left over after the payload.
    #[error("{extra} unexpected bytes after the payload")]
    TrailingBytes {
        /// Number of extra bytes.
        extra: usize,
    },
    /// The payload decoded but is not valid (e.g. the mesh it holds is not manifold).
    #[error("invalid content: {0}")]
    Invalid(String),
    /// Encoding failed.
    #[error("encoding failed: {0}")]
    Encode(String),
    /// Reading or writing the file failed.
    #[error(transparent)]
    Io(#[from] std::io::Error),
}

fn config() -> impl bincode::config::Config {
    bincode::config::standard()
}

/// Encodes `value` behind a header with `magic` and `version`.
///
/// ```
/// use mesh_topo::binary::{self, BinaryError};
///
/// let bytes = binary::encode(*b"EXAMPLE\0", 3, &vec![1.5f64, -2.0])?;
/// assert_eq!(bytes[..8], *b"EXAMPLE\0");
/// assert_eq!(bytes[8..12], 3u32.to_le_bytes());
/// let back: Vec<f64> = binary::decode(&bytes, *b"EXAMPLE\0", 3, "example")?;
/// assert_eq!(back, [1.5, -2.0]);
/// # Ok::<(), BinaryError>(())
/// ```
///
/// # Errors
/// [`BinaryError::Encode`] if the value cannot be serialized.
pub fn encode<T: Serialize>(magic: [u8; 8], version: u32, value: &T) -> Result<Vec<u8>, BinaryError> {
    let mut out = Vec::with_capacity(64);
    out.extend_from_slice(&magic);
    out.extend_from_slice(&version.to_le_bytes());
    let payload = bincode::serde::encode_to_vec(value, config()).map_err(|e| BinaryError::Encode(e.to_string()))?;
    out.extend_from_slice(&payload);
    Ok(out)
}

/// Decodes a value written by [`encode`] with the same `magic` and `version`.
/// `what` names the file kind in error messages.
///
/// ```
/// use mesh_topo::binary::{self, BinaryError};
///
/// const MAGIC: [u8; 8] = *b"EXAMPLE\0";
/// let bytes = binary::encode(MAGIC, 1, &(7u32, "seven".to_string()))?;
/// assert_eq!(binary::decode::<(u32, String)>(&bytes, MAGIC, 1, "example")?, (7, "seven".to_string()));
/// let newer = binary::decode::<(u32, String)>(&bytes, MAGIC, 2, "example");
/// assert!(matches!(newer, Err(BinaryError::UnsupportedVersion { found: 1, supported: 2 })));
/// let cut = binary::decode::<(u32, String)>(&bytes[..bytes.len() - 1], MAGIC, 1, "example");
/// assert!(matches!(cut, Err(BinaryError::Corrupted { .. })));
/// assert!(matches!(binary::decode::<u32>(b"MRS", MAGIC, 1, "example"), Err(BinaryError::TruncatedHeader { len: 3 })));
/// # Ok::<(), BinaryError>(())
/// ```
///
/// # Errors
/// Header, version, corruption and trailing-byte errors as [`BinaryError`].
pub fn decode<T: DeserializeOwned>(bytes: &[u8], magic: [u8; 8], version: u32, what: &str) -> Result<T, BinaryError> {
    if bytes.len() < 12 {
        return Err(BinaryError::TruncatedHeader { len: bytes.len() });
    }
    let found: [u8; 8] = bytes[..8].try_into().expect("internal: 8-byte slice");
    if found != magic {
        return Err(BinaryError::WrongMagic { expected: what.to_string(), found });
    }
    let file_version = u32::from_le_bytes(bytes[8..12].try_into().expect("internal: 4-byte slice"));
    if file_version != version {
        return Err(BinaryError::UnsupportedVersion { found: file_version, supported: version });
    }
    let payload = &bytes[12..];
    // serde pre-allocates sequences cautiously (bounded by a small constant), so a
    // corrupted length prefix runs out of input and fails instead of reserving memory.
    let mut reader = TrackedSlice { rest: payload, len: payload.len() };
    let value: T = bincode::serde::decode_from_reader(&mut reader, config())
        .map_err(|e| BinaryError::Corrupted { offset: 12 + reader.position(), message: describe(&e, bytes.len()) })?;
    if !reader.rest.is_empty() {
        return Err(BinaryError::TrailingBytes { extra: reader.rest.len() });
    }
    Ok(value)
}

/// A reader of the payload that knows how far decoding got, so that an error can say
/// where the payload stopped making sense (bincode's slice reader, counting).
struct TrackedSlice<'a> {
    /// What is left to read.
    rest: &'a [u8],
    /// The payload's length.
    len: usize,
}

impl TrackedSlice<'_> {
    /// Bytes consumed so far.
    fn position(&self) -> usize {
        self.len - self.rest.len()
    }
}

impl bincode::de::read::Reader for TrackedSlice<'_> {
    #[inline(always)]
    fn read(&mut self, out: &mut [u8]) -> Result<(), DecodeError> {
        if out.len() > self.rest.len() {
            return Err(DecodeError::UnexpectedEnd { additional: out.len() - self.rest.len() });
        }
        let (read, rest) = self.rest.split_at(out.len());
        out.copy_from_slice(read);
        self.rest = rest;
        Ok(())
    }

    #[inline]
    fn peek_read(&mut self, n: usize) -> Option<&[u8]> {
        self.rest.get(..n)
    }

    #[inline]
    fn consume(&mut self, n: usize) {
        self.rest = self.rest.get(n..).unwrap_or_default();
    }
}

/// What went wrong in words (the decoder's own `Display` is its `Debug`), for a file of
/// `file_len` bytes.
fn describe(error: &DecodeError, file_len: usize) -> String {
    match error {
        DecodeError::UnexpectedEnd { additional } => format!(
            "the file ends in the middle of a value ({file_len} bytes, at least {additional} more expected): it is \
             truncated"
        ),
        DecodeError::UnexpectedVariant { type_name, found, .. } => {
            format!("variant number {found} of `{type_name}` does not exist")
        }
        DecodeError::InvalidBooleanValue(value) => format!("byte {value} where a boolean (0 or 1) was expected"),
        DecodeError::Utf8 { .. } => "a text field is not valid UTF-8".to_string(),
        DecodeError::OutsideUsizeRange(value) => format!("the length {value} does not fit in memory addresses"),
        DecodeError::LimitExceeded => "a length exceeds the decoder's limit".to_string(),
        DecodeError::OtherString(message) => message.clone(),
        DecodeError::Other(message) => (*message).to_string(),
        other => format!("{other:?}"),
    }
}

/// Encodes a mesh (as its polygon soup: positions and faces in order).
///
/// ```
/// use mesh_topo::{HalfedgeMesh, PolygonSoup, binary, shapes};
///
/// let mesh = HalfedgeMesh::from_soup(&shapes::cube())?;
/// let bytes = binary::encode_mesh(&mesh)?;
/// assert_eq!(bytes[..8], binary::MESH_MAGIC);
/// // The payload is the mesh's soup, exactly as it was built from.
/// let soup: PolygonSoup = binary::decode(&bytes, binary::MESH_MAGIC, binary::MESH_VERSION, "mesh")?;
/// assert_eq!(soup, shapes::cube());
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
///
/// # Errors
/// See [`encode`].
pub fn encode_mesh(mesh: &HalfedgeMesh) -> Result<Vec<u8>, BinaryError> {
    encode(MESH_MAGIC, MESH_VERSION, &mesh.to_soup())
}

/// Decodes and validates a mesh written by [`encode_mesh`].
///
/// ```
/// use glam::DVec3;
/// use mesh_topo::{HalfedgeMesh, binary};
/// let mesh = HalfedgeMesh::from_faces(vec![DVec3::ZERO, DVec3::X, DVec3::Y], [[0u32, 1, 2]])?;
/// let bytes = binary::encode_mesh(&mesh)?;
/// assert_eq!(binary::decode_mesh(&bytes)?, mesh);
/// assert!(binary::decode_mesh(&bytes[..bytes.len() - 1]).is_err());
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
///
/// # Errors
/// See [`decode`]; a payload that is not a valid mesh gives [`BinaryError::Invalid`].
pub fn decode_mesh(bytes: &[u8]) -> Result<HalfedgeMesh, BinaryError> {
    let soup: PolygonSoup = decode(bytes, MESH_MAGIC, MESH_VERSION, "multires binary mesh")?;
    HalfedgeMesh::from_soup(&soup).map_err(|e| BinaryError::Invalid(e.to_string()))
}
