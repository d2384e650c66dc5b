//! `multires render` through the binary: a known mesh gives a PNG of the asked size whose
//! coverage and corner pixels are as expected, identical bytes on a second run, and bad
//! options are one clear error line with nothing written.

use std::path::Path;
use std::process::{Command, Output};

fn multires(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_multires"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("run multires")
}

/// Width, height and the RGB pixels of an 8-bit RGB PNG.
fn decode(path: &Path) -> (u32, u32, Vec<u8>) {
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).unwrap()));
    let mut reader = decoder.read_info().unwrap();
    let mut pixels = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut pixels).unwrap();
    assert_eq!(info.color_type, png::ColorType::Rgb);
    pixels.truncate(info.buffer_size());
    (info.width, info.height, pixels)
}

#[test]
fn a_known_mesh_renders_deterministically() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("cube.png");
    let args = ["render", "tests/data/cube_quad.off", out.to_str().unwrap(), "--size", "120x90", "--wireframe"];
    let first = multires(&args);
    assert!(first.status.success(), "{}", String::from_utf8_lossy(&first.stderr));
    let stdout = String::from_utf8(first.stdout).unwrap();
    assert!(stdout.contains("120x90"), "{stdout}");

    let (width, height, pixels) = decode(&out);
    assert_eq!((width, height), (120, 90));
    let background = [246u8, 246, 246];
    let pixel = |x: u32, y: u32| -> [u8; 3] {
        let i = 3 * (y * width + x) as usize;
        [pixels[i], pixels[i + 1], pixels[i + 2]]
    };
    // The framed cube covers the centre, not the corners.
    assert_ne!(pixel(60, 45), background);
    for (x, y) in [(0, 0), (119, 0), (0, 89), (119, 89)] {
        assert_eq!(pixel(x, y), background, "corner ({x}, {y})");
    }
    let covered = (0..height).flat_map(|y| (0..width).map(move |x| (x, y))).filter(|&(x, y)| pixel(x, y) != background);
    let coverage = covered.count() as f64 / f64::from(width * height);
    assert!((0.15..0.85).contains(&coverage), "coverage {coverage}");

    let bytes = std::fs::read(&out).unwrap();
    assert!(multires(&args).status.success());
    assert_eq!(std::fs::read(&out).unwrap(), bytes, "same input, same bytes");
}

/// The picture does not depend on the mesh's scale: a subdivided cube scaled by 2^-600,
/// 2^600 or to near `f64::MAX` gives the bytes of the unit one (at 2^-600 the normals
/// underflowed and the mesh was drawn flat).
#[test]
fn the_picture_does_not_depend_on_the_scale() {
    let dir = tempfile::tempdir().unwrap();
    let fine = dir.path().join("fine.off");
    let subdivide = ["subdivide", "tests/data/cube_quad.off", fine.to_str().unwrap(), "--scheme", "doo-sabin"];
    assert!(multires(&subdivide).status.success());
    let text = std::fs::read_to_string(&fine).unwrap();
    let scaled = |factor: f64| -> String {
        let mut vertices = None;
        let mut out = Vec::new();
        for line in text.lines() {
            let words: Vec<&str> = line.split_whitespace().collect();
            match vertices {
                _ if words.is_empty() || line.starts_with('#') || line == "OFF" => out.push(line.to_string()),
                None => {
                    vertices = Some(words[0].parse::<usize>().unwrap());
                    out.push(line.to_string());
                }
                Some(0) => out.push(line.to_string()),
                Some(left) => {
                    let p: Vec<f64> = words.iter().map(|w| w.parse::<f64>().unwrap() * factor).collect();
                    out.push(format!("{:e} {:e} {:e}", p[0], p[1], p[2]));
                    vertices = Some(left - 1);
                }
            }
        }
        let path = dir.path().join(format!("scaled-{factor:e}.off"));
        std::fs::write(&path, out.join("\n")).unwrap();
        path.to_str().unwrap().to_string()
    };
    let render = |mesh: &str| {
        let out = dir.path().join("out.png");
        let result = multires(&["render", mesh, out.to_str().unwrap(), "--size", "120x90"]);
        assert!(result.status.success(), "{}", String::from_utf8_lossy(&result.stderr));
        std::fs::read(&out).unwrap()
    };
    let unit = render(&scaled(1.0));
    for factor in [2f64.powi(-600), 2f64.powi(600), 2f64.powi(1020)] {
        assert!(render(&scaled(factor)) == unit, "scaled by {factor:e}");
    }
}

#[test]
fn side_by_side_panels_share_the_height() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("pair.png");
    let run = multires(&[
        "render",
        "tests/data/cube_quad.off",
        out.to_str().unwrap(),
        "--size",
        "64x48",
        "--view=30,20",
        "--side-by-side",
        "tests/data/cube_poly.off",
    ]);
    assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
    let (width, height, _) = decode(&out);
    assert_eq!((width, height), (128, 48));
}

/// Runs `multires render cube_quad.off never.png EXTRA...`, which must fail with one
/// line on stderr and write nothing; the line.
fn fails_with_one_line(extra: &[&str]) -> String {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("never.png");
    let mut args = vec!["render", "tests/data/cube_quad.off", out.to_str().unwrap()];
    args.extend(extra);
    let run = multires(&args);
    assert!(!run.status.success(), "{extra:?}");
    let stderr = String::from_utf8(run.stderr).unwrap();
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(stderr.starts_with("multires: "), "{stderr}");
    assert!(!out.exists(), "{extra:?} wrote a file");
    stderr
}

#[test]
fn bad_options_are_one_line_and_write_nothing() {
    for extra in [["--size", "0x10"], ["--size", "big"], ["--view", "0,120"]] {
        fails_with_one_line(&extra);
    }
}

#[test]
fn oversized_images_name_the_pixel_limit() {
    // Used to abort allocating 58 GB of supersampled buffers.
    let sizes: [&[&str]; 2] =
        [&["--size", "16384x16384"], &["--size", "4096x2048", "--side-by-side", "tests/data/cube_poly.off"]];
    for extra in sizes {
        let stderr = fails_with_one_line(extra);
        assert!(stderr.contains("--size") && stderr.contains("at most 8388608"), "{stderr}");
    }
}
