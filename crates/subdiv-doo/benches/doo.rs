//! Doo-Sabin benches: forward subdivision (levels 1-3) on the bunny and on a mesh of more
//! than a million faces, single-threaded and with all threads.
//!
//! `doo_multires` times one reverse step (`decompose`, one level; automatic choice of the
//! reading, and with a given seed face) and its reconstruction at four sizes, next to the
//! forward step of the same size; the throughput is in fine vertices, so a flat
//! elements-per-second figure across sizes is linear time. The fine meshes are written
//! by `subdivide`, so they are in the canonical order (the fast path of the reversal);
//! `decompose_renumbered` times the general path on the same mesh renumbered, and
//! `forward_renumbered` the forward step of the coarse mesh renumbered the same way.
//!
//! `doo_multilevel` times a pyramid of three levels (`decompose` to three levels and to
//! the maximum depth, and `reconstruct` of all three) at three sizes, next to three levels
//! of forward subdivision from the same base mesh; the throughput is in finest vertices.
//!
//! "The forward Doo-Sabin step of the same size" is one level of subdivision of the
//! coarse mesh, to the very fine mesh (connectivity and positions) that `decompose` takes
//! apart and `reconstruct` rebuilds, each starting from what its user holds: `forward`
//! (`subdivide`) and `decompose` start from a built `HalfedgeMesh`; `reconstruct` starts
//! from the `DooPyramid`, whose base mesh is a polygon soup that it validates, so its
//! counterpart is `forward_soup` (`subdivide_soup`: the coarse soup validated, then
//! subdivided), as in the reverse Loop bench; `reconstruct_prepared` starts from the
//! pyramid with its base connectivity built (`DooPyramid::prepare`), so its counterpart
//! is `forward`. Compare in the same run and with the same number of threads:
//! `decompose*_1thread` with `forward_1thread`, `reconstruct_1thread` with
//! `forward_soup_1thread`, `reconstruct_prepared_1thread` with `forward_1thread`,
//! `decompose_renumbered_1thread` with `forward_renumbered_1thread`, and
//! `decompose_soup_1thread` (`decompose_soup`: the fine mesh as a polygon soup, as read
//! from a file, its half-edges computed from its face list) with `forward_soup_1thread`.
//!
//! Fresh memory: every call hands its arrays back to the allocator, and glibc returns the
//! top of its heap to the kernel once more than its trim threshold is free there (by
//! default twice the largest block it has unmapped so far in the process, at most
//! 64 MiB). A call whose peak is above that finds its memory unmapped on the next call
//! and faults every page in again, which the kernel also clears. A decomposition keeps
//! its scratch and its output alive at its peak, the forward step mostly its output, so
//! the decompositions are the ones that pay, and which sizes pay depends on what the
//! process allocated before: in a run of all four `doo_multires` sizes, smallest first,
//! the largest seeded decomposition took 34-50 ms, against 18-22 ms run alone or with
//! `MALLOC_TRIM_THRESHOLD_` and `MALLOC_MMAP_THRESHOLD_` fixed at 4 GiB, while the
//! forward step did not change; the first level of a three-level `decompose` costs up to
//! 1.8x the same reversal run alone for the same reason. The benches keep the default
//! allocator settings, as a user's program has them: read the ratios with this in mind.
//!
//! The automatic choice costs the seeded reversal plus the part of the dual reading's
//! sum that it runs before that sum reaches the first reading's total (see
//! `subdiv_doo::reverse`), and that part depends on the input, not only on its size. On
//! these meshes every fine vertex is moved by noise of size `0.05 / n`, whose detail
//! energy is the same at every size while the dual reading's own (the surface's
//! curvature, seen from the wrong reading) shrinks with the faces: the dual sum stops
//! after 13.4%, 21.9%, 28.3% and 30.8% of its groups at the four sizes, smallest first,
//! so the automatic choice's time per fine vertex grows with the size here. A mesh
//! whose two readings differ more stops sooner; on a mesh refined without noise the
//! first reading's details are zero and no other reading is tried.
//! `decompose_edited` times the automatic choice on the refinement with one fine vertex
//! moved by `0.5 / n` (the reverse Doo paper's figure): the first reading's details are
//! zero but around that vertex, and the dual reading's sum stops after 33-34 of its
//! 4096-262 144 groups, so this row costs about what the seeded one does.
//!
//! Run with `cargo bench -p subdiv-doo --bench doo`. The inputs are built before timing;
//! the timed call is `subdivide` on an already built half-edge mesh (the counterpart of
//! CGAL's `DooSabin_subdivision` on a `Surface_mesh`).

use std::hint::black_box;
use std::time::Duration;

use criterion::Throughput;
use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use mesh_topo::shapes::{self, CellKind};
use mesh_topo::testing::scramble;
use mesh_topo::{DVec3, HalfedgeMesh, PolygonSoup};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use subdiv_doo::pyramid::{DecomposeOptions, decompose, decompose_soup};
use subdiv_doo::{BoundaryRule, DooOptions, FaceRule, subdivide, subdivide_soup};

/// The bunny of `tests/data` (a minimal OBJ reader: positions and faces only).
fn bunny() -> HalfedgeMesh {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../tests/data/bunny.obj");
    let text = std::fs::read_to_string(path).expect("tests/data/bunny.obj");
    let mut positions = Vec::new();
    let mut faces: Vec<Vec<u32>> = Vec::new();
    for line in text.lines() {
        let mut parts = line.split_whitespace();
        match parts.next() {
            Some("v") => {
                let c: Vec<f64> = parts.take(3).map(|t| t.parse().unwrap()).collect();
                positions.push(DVec3::new(c[0], c[1], c[2]));
            }
            Some("f") => faces.push(parts.map(|t| t.parse::<u32>().unwrap() - 1).collect()),
            _ => {}
        }
    }
    HalfedgeMesh::from_soup(&PolygonSoup::from_faces(positions, faces)).unwrap()
}

/// A closed triangulated torus of 1024 x 512 x 2 = 1,048,576 faces.
fn big_torus() -> HalfedgeMesh {
    HalfedgeMesh::from_soup(&shapes::torus(1024, 512, CellKind::Triangles).unwrap()).unwrap()
}

fn single_thread() -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap()
}

fn forward(c: &mut Criterion) {
    let one = single_thread();
    let mut group = c.benchmark_group("doo_forward");
    group.sample_size(10).measurement_time(Duration::from_secs(3)).warm_up_time(Duration::from_secs(1));
    let bunny = bunny();
    for levels in 1..=3 {
        let options = DooOptions::new(FaceRule::DooSabin, levels);
        group.bench_with_input(BenchmarkId::new("bunny_1thread", levels), &levels, |b, _| {
            b.iter(|| one.install(|| subdivide(black_box(&bunny), &options).unwrap()))
        });
        group.bench_with_input(BenchmarkId::new("bunny", levels), &levels, |b, _| {
            b.iter(|| subdivide(black_box(&bunny), &options).unwrap())
        });
    }
    let torus = big_torus();
    for levels in 1..=2 {
        let options = DooOptions::new(FaceRule::DooSabin, levels);
        group.bench_with_input(BenchmarkId::new("torus1M_1thread", levels), &levels, |b, _| {
            b.iter(|| one.install(|| subdivide(black_box(&torus), &options).unwrap()))
        });
        group.bench_with_input(BenchmarkId::new("torus1M", levels), &levels, |b, _| {
            b.iter(|| subdivide(black_box(&torus), &options).unwrap())
        });
    }
    group.finish();
}

/// A triangulated torus of `n x m x 2` faces with every vertex moved at random (fixed
/// seed), and its Doo-Sabin refinement with every fine vertex moved too: a fine mesh with
/// non-zero details at every vertex. Also the refinement with one fine vertex moved
/// instead (the reverse Doo paper's figure: subdivide, move one vertex, reverse).
fn multires_meshes(n: u32, m: u32) -> (HalfedgeMesh, HalfedgeMesh, HalfedgeMesh) {
    let mut rng = ChaCha8Rng::seed_from_u64(0x0d00_5ab1 + n as u64);
    let mut jitter = |positions: &mut [DVec3], amount: f64| {
        for p in positions {
            *p += amount * DVec3::new(rng.random::<f64>() - 0.5, rng.random::<f64>() - 0.5, rng.random::<f64>() - 0.5);
        }
    };
    let mut coarse = HalfedgeMesh::from_soup(&shapes::torus(n, m, CellKind::Triangles).unwrap()).unwrap();
    jitter(coarse.positions_mut(), 0.2 / n as f64);
    let refined = subdivide(&coarse, &DooOptions::new(FaceRule::DooSabin, 1)).unwrap().to_mesh().unwrap();
    let mut fine = refined.clone();
    jitter(fine.positions_mut(), 0.05 / n as f64);
    let mut edited = refined;
    edited.positions_mut()[100].z += 0.5 / n as f64;
    (coarse, fine, edited)
}

fn multires(c: &mut Criterion) {
    let one = single_thread();
    let mut group = c.benchmark_group("doo_multires");
    group.sample_size(10).measurement_time(Duration::from_secs(3)).warm_up_time(Duration::from_secs(1));
    for (n, m) in [(64u32, 32u32), (128, 64), (256, 128), (512, 256)] {
        let (coarse, fine, edited) = multires_meshes(n, m);
        let fine_vertices = fine.vertex_count();
        group.throughput(Throughput::Elements(fine_vertices as u64));
        let forward_options = DooOptions::new(FaceRule::DooSabin, 1);
        let options = DecomposeOptions::levels(FaceRule::DooSabin, 1);
        // Face 0 of a mesh written by `subdivide` is the F_F face of coarse face 0.
        let seeded = DecomposeOptions { seeds: vec![0], ..options.clone() };
        let pyramid = decompose(&fine, &options).unwrap().pyramid;
        group.bench_with_input(BenchmarkId::new("forward_1thread", fine_vertices), &coarse, |b, coarse| {
            b.iter(|| one.install(|| subdivide(black_box(coarse), &forward_options).unwrap()))
        });
        group.bench_with_input(BenchmarkId::new("decompose_1thread", fine_vertices), &fine, |b, fine| {
            b.iter(|| one.install(|| decompose(black_box(fine), &options).unwrap()))
        });
        group.bench_with_input(BenchmarkId::new("decompose_seed_1thread", fine_vertices), &fine, |b, fine| {
            b.iter(|| one.install(|| decompose(black_box(fine), &seeded).unwrap()))
        });
        group.bench_with_input(BenchmarkId::new("decompose_edited_1thread", fine_vertices), &edited, |b, edited| {
            b.iter(|| one.install(|| decompose(black_box(edited), &options).unwrap()))
        });
        // The same mesh with its vertices renumbered and its faces rotated: not in the
        // canonical order, so the general path (search and face matching) runs.
        let renumbered = HalfedgeMesh::from_soup(&scramble(fine.to_soup(), 7, 0.0)).unwrap();
        group.bench_with_input(
            BenchmarkId::new("decompose_renumbered_1thread", fine_vertices),
            &renumbered,
            |b, fine| b.iter(|| one.install(|| decompose(black_box(fine), &options).unwrap())),
        );
        // Its forward counterpart: the coarse mesh renumbered the same way, subdivided
        // (scattered reads on both sides).
        let coarse_renumbered = HalfedgeMesh::from_soup(&scramble(coarse.to_soup(), 7, 0.0)).unwrap();
        group.bench_with_input(
            BenchmarkId::new("forward_renumbered_1thread", fine_vertices),
            &coarse_renumbered,
            |b, coarse| b.iter(|| one.install(|| subdivide(black_box(coarse), &forward_options).unwrap())),
        );
        let coarse_soup = coarse.to_soup();
        group.bench_with_input(BenchmarkId::new("forward_soup_1thread", fine_vertices), &coarse_soup, |b, soup| {
            b.iter(|| one.install(|| subdivide_soup(black_box(soup), &forward_options).unwrap()))
        });
        // From the fine soup, as read from a file (its half-edges computed from the face
        // list, no half-edge mesh built): against `forward_soup`, both starting from a soup.
        let fine_soup = fine.to_soup();
        group.bench_with_input(BenchmarkId::new("decompose_soup_1thread", fine_vertices), &fine_soup, |b, soup| {
            b.iter(|| one.install(|| decompose_soup(black_box(soup), &options).unwrap()))
        });
        group.bench_with_input(BenchmarkId::new("reconstruct_1thread", fine_vertices), &pyramid, |b, pyramid| {
            b.iter(|| one.install(|| black_box(pyramid).reconstruct(1, None).unwrap()))
        });
        // The base connectivity built once, as `forward` starts from a built mesh.
        let prepared = pyramid.prepare().unwrap();
        group.bench_with_input(
            BenchmarkId::new("reconstruct_prepared_1thread", fine_vertices),
            &prepared,
            |b, prepared| b.iter(|| one.install(|| black_box(prepared).reconstruct(1, None).unwrap())),
        );
        group.bench_with_input(BenchmarkId::new("decompose", fine_vertices), &fine, |b, fine| {
            b.iter(|| decompose(black_box(fine), &options).unwrap())
        });
        group.bench_with_input(BenchmarkId::new("forward", fine_vertices), &coarse, |b, coarse| {
            b.iter(|| subdivide(black_box(coarse), &forward_options).unwrap())
        });
        group.bench_with_input(BenchmarkId::new("decompose_seed", fine_vertices), &fine, |b, fine| {
            b.iter(|| decompose(black_box(fine), &seeded).unwrap())
        });
        group.bench_with_input(BenchmarkId::new("reconstruct", fine_vertices), &pyramid, |b, pyramid| {
            b.iter(|| black_box(pyramid).reconstruct(1, None).unwrap())
        });
    }
    group.finish();
}

/// The two boundary rules on an open quad grid of 512 x 512 faces (one step forward, and
/// one decomposition level of the step with every fine vertex moved, automatic and with
/// a given seed face), one thread: the
/// Chaikin rule rebuilds the next level's corner arrays from the soup and reverses through
/// the general path (the ring stripped, the rest searched), the Shrink rule has the index
/// arithmetic and, for the decomposition of a canonical mesh, the streaming path.
fn boundary_rules(c: &mut Criterion) {
    let one = single_thread();
    let mut group = c.benchmark_group("doo_boundary");
    group.sample_size(10).measurement_time(Duration::from_secs(3)).warm_up_time(Duration::from_secs(1));
    let grid = HalfedgeMesh::from_soup(&shapes::grid(512, 512, CellKind::Quads).unwrap()).unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(0xb0_0d);
    for boundary in [BoundaryRule::Shrink, BoundaryRule::Chaikin] {
        let options = DooOptions::new(FaceRule::DooSabin, 1).with_boundary(boundary);
        group.bench_function(BenchmarkId::new("forward_1thread", boundary), |b| {
            b.iter(|| one.install(|| subdivide(black_box(&grid), &options).unwrap()))
        });
        let mut fine = subdivide(&grid, &options).unwrap().to_mesh().unwrap();
        for p in fine.positions_mut() {
            p.z += 1e-3 * (rng.random::<f64>() - 0.5);
        }
        let decompose_options = DecomposeOptions::levels(FaceRule::DooSabin, 1).with_boundary(boundary);
        group.bench_function(BenchmarkId::new("decompose_1thread", boundary), |b| {
            b.iter(|| one.install(|| decompose(black_box(&fine), &decompose_options).unwrap()))
        });
        // Face 0 is the F_F face of coarse face 0 under both rules: the reading given.
        let seeded = DecomposeOptions { seeds: vec![0], ..decompose_options.clone() };
        group.bench_function(BenchmarkId::new("decompose_seed_1thread", boundary), |b| {
            b.iter(|| one.install(|| decompose(black_box(&fine), &seeded).unwrap()))
        });
    }
    group.finish();
}

/// Three levels: a torus of `n x m x 2` triangles, refined three times with every finest
/// vertex moved (the pyramid of `multires_meshes`'s one level, three levels deep).
fn multilevel(c: &mut Criterion) {
    let one = single_thread();
    let mut group = c.benchmark_group("doo_multilevel");
    group.sample_size(10).measurement_time(Duration::from_secs(3)).warm_up_time(Duration::from_secs(1));
    for (n, m) in [(32u32, 16u32), (64, 32), (128, 64)] {
        let mut rng = ChaCha8Rng::seed_from_u64(0x3_1e7e1 + n as u64);
        let base = HalfedgeMesh::from_soup(&shapes::torus(n, m, CellKind::Triangles).unwrap()).unwrap();
        let forward_options = DooOptions::new(FaceRule::DooSabin, 3);
        let mut fine = subdivide(&base, &forward_options).unwrap().to_mesh().unwrap();
        for p in fine.positions_mut() {
            *p += (0.01 / n as f64) * DVec3::new(rng.random::<f64>() - 0.5, rng.random::<f64>() - 0.5, 0.0);
        }
        let fine_vertices = fine.vertex_count();
        group.throughput(Throughput::Elements(fine_vertices as u64));
        let three = DecomposeOptions::levels(FaceRule::DooSabin, 3);
        let deepest = DecomposeOptions::max(FaceRule::DooSabin);
        let pyramid = decompose(&fine, &three).unwrap().pyramid;
        group.bench_with_input(BenchmarkId::new("forward3_1thread", fine_vertices), &base, |b, base| {
            b.iter(|| one.install(|| subdivide(black_box(base), &forward_options).unwrap()))
        });
        group.bench_with_input(BenchmarkId::new("decompose3_1thread", fine_vertices), &fine, |b, fine| {
            b.iter(|| one.install(|| decompose(black_box(fine), &three).unwrap()))
        });
        group.bench_with_input(BenchmarkId::new("decompose_max_1thread", fine_vertices), &fine, |b, fine| {
            b.iter(|| one.install(|| decompose(black_box(fine), &deepest).unwrap()))
        });
        group.bench_with_input(BenchmarkId::new("reconstruct3_1thread", fine_vertices), &pyramid, |b, pyramid| {
            b.iter(|| one.install(|| black_box(pyramid).reconstruct(3, None).unwrap()))
        });
    }
    group.finish();
}

criterion_group!(benches, forward, multires, boundary_rules, multilevel);
criterion_main!(benches);
