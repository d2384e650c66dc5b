//! Fuzz the PLY reader: never panic; whatever reads must write and read back to the
//! same soup, and building a mesh from it must not panic either.

#![no_main]

use libfuzzer_sys::fuzz_target;
use mesh_topo::io::Format;

mod common;

fuzz_target!(|data: &[u8]| common::check_reader(data, Format::Ply));
