//! Reading and writing OBJ, OFF and ascii and binary PLY from and to memory, in faces per second
//! (so the file system is not measured); the text readers and writers also on one
//! thread, beside the default pool.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use mesh_topo::io::{self, Format, PlyEncoding, WriteOptions};
use std::hint::black_box;
use std::time::Duration;

mod fixtures;

const FORMATS: [(&str, Format, PlyEncoding); 4] = [
    ("obj", Format::Obj, PlyEncoding::Ascii),
    ("off", Format::Off, PlyEncoding::Ascii),
    ("ply-ascii", Format::Ply, PlyEncoding::Ascii),
    ("ply-binary", Format::Ply, PlyEncoding::BinaryLittleEndian),
];

fn read_and_write(c: &mut Criterion) {
    let soups = fixtures::soups();
    // (A system that cannot start one more thread has nothing to time here: reported.)
    let one_thread = match rayon::ThreadPoolBuilder::new().num_threads(1).build() {
        Ok(pool) => pool,
        Err(error) => {
            eprintln!("read and write: skipped, no one-thread pool: {error}");
            return;
        }
    };
    for (operation, writing) in [("read", false), ("write", true)] {
        let mut group = c.benchmark_group(operation);
        group.sample_size(10).measurement_time(Duration::from_secs(8));
        for (name, soup) in &soups {
            group.throughput(Throughput::Elements(soup.face_count() as u64));
            for (format_name, format, ply_encoding) in FORMATS {
                let options = WriteOptions { ply_encoding };
                let id = format!("{format_name}/{name}");
                // Checked once, outside the clock: a fixture that does not round-trip is
                // reported and skipped (the timed loops then only return the results).
                let mut bytes = Vec::new();
                let round_trip = io::write_to(&mut bytes, soup, format, &options)
                    .map_err(|e| e.to_string())
                    .and_then(|()| io::read_bytes(&bytes, format).map_err(|e| e.to_string()));
                if let Err(message) = round_trip {
                    eprintln!("{operation} {id}: skipped, the fixture does not round-trip: {message}");
                    continue;
                }
                if writing {
                    let write = || {
                        let mut out = Vec::with_capacity(bytes.len());
                        let written = io::write_to(&mut out, black_box(soup), format, &options);
                        (written, out)
                    };
                    group.bench_function(&id, |b| b.iter(write));
                    // The text formats are formatted on the pool's threads: one thread
                    // alone, for the ratio.
                    if ply_encoding == PlyEncoding::Ascii {
                        group.bench_function(format!("{format_name}-1thread/{name}"), |b| {
                            b.iter(|| one_thread.install(write))
                        });
                    }
                } else {
                    let read = || io::read_bytes(black_box(&bytes), format);
                    group.bench_function(id, |b| b.iter(read));
                    // Large text files are read in pieces on the pool's threads.
                    if ply_encoding == PlyEncoding::Ascii {
                        group.bench_function(format!("{format_name}-1thread/{name}"), |b| {
                            b.iter(|| one_thread.install(read))
                        });
                    }
                }
            }
        }
        group.finish();
    }
}

criterion_group!(benches, read_and_write);
criterion_main!(benches);
