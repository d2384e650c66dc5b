//! The binary mesh format: one test per way a file can be wrong, each a typed error
//! (never a panic) naming what is wrong.

use mesh_topo::binary::{self, BinaryError, MESH_MAGIC, MESH_VERSION};
use mesh_topo::{DVec3, HalfedgeMesh, PolygonSoup, shapes};

fn cube() -> HalfedgeMesh {
    HalfedgeMesh::from_soup(&shapes::cube()).unwrap()
}

fn encoded_cube() -> Vec<u8> {
    binary::encode_mesh(&cube()).unwrap()
}

#[test]
fn binary_round_trip_keeps_the_mesh() {
    assert_eq!(binary::decode_mesh(&encoded_cube()).unwrap(), cube());
}

#[test]
fn binary_truncated_header() {
    let bytes = encoded_cube();
    for len in [0, 7, 11] {
        let e = binary::decode_mesh(&bytes[..len]).unwrap_err();
        assert!(matches!(e, BinaryError::TruncatedHeader { len: l } if l == len), "{e}");
    }
}

#[test]
fn binary_wrong_magic() {
    let mut bytes = encoded_cube();
    bytes[..8].copy_from_slice(b"OFF\n3 1 ");
    let e = binary::decode_mesh(&bytes).unwrap_err();
    assert!(matches!(e, BinaryError::WrongMagic { found, .. } if &found == b"OFF\n3 1 "), "{e}");
    assert!(e.to_string().contains("not a multires binary mesh file"), "{e}");
}

#[test]
fn binary_unsupported_version() {
    let mut bytes = encoded_cube();
    bytes[8..12].copy_from_slice(&(MESH_VERSION + 1).to_le_bytes());
    let e = binary::decode_mesh(&bytes).unwrap_err();
    assert!(
        matches!(e, BinaryError::UnsupportedVersion { found, supported } if found == MESH_VERSION + 1 && supported == MESH_VERSION),
        "{e}"
    );
}

#[test]
fn binary_truncated_payload_is_corrupted() {
    let bytes = encoded_cube();
    let mut offsets = Vec::new();
    for cut in 12..bytes.len() {
        let e = binary::decode_mesh(&bytes[..cut]).unwrap_err();
        // Named where decoding stopped: inside the data that is there, and as a truncation.
        match &e {
            BinaryError::Corrupted { offset, message } => {
                assert!((12..=cut).contains(offset) && message.contains("truncated"), "cut at {cut}: {e}");
                offsets.push(*offset);
            }
            _ => panic!("cut at {cut}: {e}"),
        }
    }
    // The later the cut, the later the place named (not always the start of the payload).
    assert!(offsets.windows(2).all(|w| w[0] <= w[1]) && offsets.last() > offsets.first(), "{offsets:?}");
}

#[test]
fn binary_huge_length_prefix_is_corrupted_not_an_allocation() {
    // Header, then a varint length prefix of u64::MAX for the positions.
    let mut bytes = MESH_MAGIC.to_vec();
    bytes.extend_from_slice(&MESH_VERSION.to_le_bytes());
    bytes.push(253);
    bytes.extend_from_slice(&u64::MAX.to_le_bytes());
    let e = binary::decode_mesh(&bytes).unwrap_err();
    assert!(matches!(e, BinaryError::Corrupted { .. }), "{e}");
}

#[test]
fn binary_trailing_bytes() {
    let mut bytes = encoded_cube();
    bytes.extend_from_slice(&[0, 0, 0]);
    let e = binary::decode_mesh(&bytes).unwrap_err();
    assert!(matches!(e, BinaryError::TrailingBytes { extra: 3 }), "{e}");
}

#[test]
fn binary_payload_that_is_not_a_mesh_is_invalid() {
    // A well-formed file whose soup has an edge shared by three faces.
    let soup = PolygonSoup::from_faces(
        vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::NEG_Y, DVec3::Z],
        [[0u32, 1, 2], [1, 0, 3], [0, 1, 4]],
    );
    let bytes = binary::encode(MESH_MAGIC, MESH_VERSION, &soup).unwrap();
    let e = binary::decode_mesh(&bytes).unwrap_err();
    assert!(matches!(&e, BinaryError::Invalid(message) if message.contains("non-manifold edge")), "{e}");
    assert!(HalfedgeMesh::from_soup(&soup).is_err());
}

#[test]
fn binary_bad_values_are_named_with_their_place() {
    const MAGIC: [u8; 8] = *b"EXAMPLE\0";
    // (u32, bool, u32): the boolean is the payload's second byte, the file's 14th.
    let mut bytes = binary::encode(MAGIC, 1, &(7u32, true, 9u32)).unwrap();
    assert_eq!(bytes[13], 1);
    bytes[13] = 5;
    let e = binary::decode::<(u32, bool, u32)>(&bytes, MAGIC, 1, "example").unwrap_err();
    assert!(
        matches!(&e, BinaryError::Corrupted { offset: 14, message } if message.contains("byte 5 where a boolean")),
        "{e}"
    );
    // A string that is not UTF-8, after its length prefix.
    let mut bytes = binary::encode(MAGIC, 1, &"abc".to_string()).unwrap();
    bytes[14] = 0xff;
    let e = binary::decode::<String>(&bytes, MAGIC, 1, "example").unwrap_err();
    assert!(matches!(&e, BinaryError::Corrupted { offset: 16, message } if message.contains("not valid UTF-8")), "{e}");
}
