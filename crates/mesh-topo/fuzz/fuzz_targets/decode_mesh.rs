//! Fuzz the binary mesh decoder on the payload (the header is put in front): never
//! panic; a payload that fails to decode is reported at a byte inside the file; a mesh
//! that decodes is valid, and encodes and decodes back equal.

#![no_main]

use libfuzzer_sys::fuzz_target;
use mesh_topo::binary::{self, BinaryError};

fuzz_target!(|payload: &[u8]| {
    let mut bytes = binary::MESH_MAGIC.to_vec();
    bytes.extend_from_slice(&binary::MESH_VERSION.to_le_bytes());
    bytes.extend_from_slice(payload);
    match binary::decode_mesh(&bytes) {
        Ok(mesh) => {
            mesh.validate().expect("a decoded mesh is valid");
            let again = binary::encode_mesh(&mesh).expect("a decoded mesh encodes");
            assert_eq!(binary::decode_mesh(&again).expect("an encoded mesh decodes"), mesh);
        }
        Err(BinaryError::Corrupted { offset, message }) => {
            assert!((12..=bytes.len()).contains(&offset), "byte {offset} outside the payload of {}", bytes.len());
            assert!(!message.is_empty(), "a corrupted payload says what is wrong");
        }
        Err(error) => {
            let _ = error.to_string();
        }
    }
});
