//! Golden files: text outputs compared with the blessed copies in `tests/golden/`
//! (numbers within a relative tolerance of 1e-12). Re-bless with
//! `cargo xtask golden --bless` and review the diff.

mod common;

use multires::mesh::HalfedgeMesh;
use multires::mesh::io::{self, Format, PlyEncoding, WriteOptions};
use multires::mesh::shapes::{self, CellKind};

#[test]
fn topology_of_procedural_shapes() {
    let mut text = String::new();
    for (name, soup) in [
        ("tetrahedron", shapes::tetrahedron()),
        ("cube", shapes::cube()),
        ("icosahedron", shapes::icosahedron()),
        ("grid-mixed-4x3", shapes::grid(4, 3, CellKind::Mixed).unwrap()),
        ("torus-quads-8x5", shapes::torus(8, 5, CellKind::Quads).unwrap()),
    ] {
        let stats = HalfedgeMesh::from_soup(&soup).unwrap().topology_stats();
        text.push_str(&format!("{name} {}\n", serde_json::to_string(&stats).unwrap()));
    }
    common::check_golden("shapes-topology.txt", &text);
}

/// What the writers print for a small polygonal mesh, in each text format.
#[test]
fn cube_poly_written_in_text_formats() {
    let (soup, report) = io::read_soup(common::data("cube_poly.off")).unwrap();
    assert!(report.is_lossless());
    for (name, format) in
        [("cube_poly.obj", Format::Obj), ("cube_poly.off", Format::Off), ("cube_poly.ply", Format::Ply)]
    {
        let mut bytes = Vec::new();
        io::write_to(&mut bytes, &soup, format, &WriteOptions { ply_encoding: PlyEncoding::Ascii }).unwrap();
        common::check_golden(name, &String::from_utf8(bytes).unwrap());
    }
}

/// `multires info --json` on a polygonal genus-2 mesh.
#[test]
fn info_json_of_double_torus() {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_multires"))
        .args(["info", "tests/data/double-torus-example.off", "--json"])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    common::check_golden("info-double-torus.json", &String::from_utf8(out.stdout).unwrap());
}
