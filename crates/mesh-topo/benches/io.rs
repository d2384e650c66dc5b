//! Reading and writing OBJ, OFF and binary PLY from and to memory, in faces per second
//! (so the file system is not measured).

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use mesh_topo::io::{self, Format, PlyEncoding, WriteOptions};
use std::hint::black_box;
use std::time::Duration;

mod fixtures;

const FORMATS: [(&str, Format, PlyEncoding); 3] = [
    ("obj", Format::Obj, PlyEncoding::Ascii),
    ("off", Format::Off, PlyEncoding::Ascii),
    ("ply-binary", Format::Ply, PlyEncoding::BinaryLittleEndian),
];

fn read_and_write(c: &mut Criterion) {
    let soups = fixtures::soups();
    for (operation, writing) in [("read", false), ("write", true)] {
        let mut group = c.benchmark_group(operation);
        group.sample_size(10).measurement_time(Duration::from_secs(8));
        for (name, soup) in &soups {
            group.throughput(Throughput::Elements(soup.face_count() as u64));
            for (format_name, format, ply_encoding) in FORMATS {
                let options = WriteOptions { ply_encoding };
                let mut bytes = Vec::new();
                io::write_to(&mut bytes, soup, format, &options).expect("writable");
                let id = format!("{format_name}/{name}");
                if writing {
                    group.bench_function(id, |b| {
                        b.iter(|| {
                            let mut out = Vec::with_capacity(bytes.len());
                            io::write_to(&mut out, black_box(soup), format, &options).expect("writable");
                            out
                        })
                    });
                } else {
                    group.bench_function(id, |b| {
                        b.iter(|| io::read_bytes(black_box(&bytes), format).expect("readable"))
                    });
                }
            }
        }
        group.finish();
    }
}

criterion_group!(benches, read_and_write);
criterion_main!(benches);
