//! A small deterministic software rasterizer for `multires render` and the demo's
//! pictures: orthographic camera from an azimuth/elevation pair, z-buffer, flat or smooth
//! (Gouraud) Lambert shading with two-sided lighting, optional depth-tested wireframe,
//! 3x3 supersampling, PNG output.
//!
//! Everything is plain `f64` arithmetic on the CPU in a fixed order, so the same mesh
//! and options give the same bytes on every machine.

use std::io::BufWriter;
use std::path::Path;

use glam::{DVec2, DVec3};
use mesh_topo::PolygonSoup;

use super::{CliError, CliResult};

/// How faces are shaded.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Shading {
    /// One normal per face (shows the facets).
    Flat,
    /// Vertex normals (area-weighted averages) interpolated across faces.
    Smooth,
}

/// Rendering options.
#[derive(Debug, Clone)]
pub struct RenderOptions {
    /// Output width in pixels.
    pub width: u32,
    /// Output height in pixels.
    pub height: u32,
    /// Camera azimuth in degrees (rotation about +z, 0 looks along -y).
    pub azimuth: f64,
    /// Camera elevation in degrees (0 = horizontal, 90 = from above).
    pub elevation: f64,
    /// Face shading.
    pub shading: Shading,
    /// Draw the edges on top of the shaded surface.
    pub wireframe: bool,
}

impl Default for RenderOptions {
    fn default() -> Self {
        Self { width: 800, height: 600, azimuth: 30.0, elevation: 20.0, shading: Shading::Smooth, wireframe: false }
    }
}

/// An RGB image, rows top to bottom.
#[derive(Debug, Clone, PartialEq)]
pub struct Image {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `width * height` RGB triples.
    pub pixels: Vec<[u8; 3]>,
}

/// Background colour (light grey).
pub const BACKGROUND: [u8; 3] = [246, 246, 246];
const FRONT_COLOUR: DVec3 = DVec3::new(0.55, 0.68, 0.85);
const BACK_COLOUR: DVec3 = DVec3::new(0.85, 0.62, 0.50);
const WIRE_COLOUR: DVec3 = DVec3::new(0.12, 0.14, 0.18);
const SUPERSAMPLE: u32 = 3;
/// Most pixels of a `multires render` image (all panels together, e.g. 4096x2048):
/// 3x3 supersampling keeps nine colours and depths, 288 bytes, per pixel, so this
/// bounds the working memory to about 2.4 GB.
pub const MAX_PIXELS: u64 = 1 << 23;

impl Image {
    /// The pixel at column `x`, row `y`.
    pub fn pixel(&self, x: u32, y: u32) -> [u8; 3] {
        self.pixels[(y * self.width + x) as usize]
    }

    /// Fraction of pixels that differ from the background.
    pub fn coverage(&self) -> f64 {
        self.pixels.iter().filter(|&&p| p != BACKGROUND).count() as f64 / self.pixels.len() as f64
    }

    /// Places images next to each other, left to right (heights must agree).
    pub fn side_by_side(images: &[Image]) -> Image {
        let height = images.iter().map(|i| i.height).max().unwrap_or(0);
        let width = images.iter().map(|i| i.width).sum();
        let mut pixels = vec![BACKGROUND; (width * height) as usize];
        let mut x0 = 0;
        for image in images {
            for y in 0..image.height {
                for x in 0..image.width {
                    pixels[(y * width + x0 + x) as usize] = image.pixel(x, y);
                }
            }
            x0 += image.width;
        }
        Image { width, height, pixels }
    }

    /// Writes the image as an 8-bit RGB PNG.
    pub fn write_png(&self, path: &Path) -> std::io::Result<()> {
        let file = std::fs::File::create(path)?;
        let mut encoder = png::Encoder::new(BufWriter::new(file), self.width, self.height);
        encoder.set_color(png::ColorType::Rgb);
        encoder.set_depth(png::BitDepth::Eight);
        let mut writer = encoder.write_header().map_err(std::io::Error::other)?;
        let bytes: Vec<u8> = self.pixels.iter().flatten().copied().collect();
        writer.write_image_data(&bytes).map_err(std::io::Error::other)?;
        writer.finish().map_err(std::io::Error::other)
    }
}

/// Orthographic camera: world -> (pixel x, pixel y, depth), depth growing away from the viewer.
#[derive(Debug, Clone, Copy)]
pub struct Camera {
    right: DVec3,
    up: DVec3,
    forward: DVec3,
    centre: DVec3,
    scale: f64,
    half_size: DVec2,
}

impl Camera {
    /// A camera looking at the bounding box of `positions` from the given direction,
    /// framing it with a margin in an image of the given size (in pixels).
    pub fn framing(positions: &[DVec3], azimuth: f64, elevation: f64, width: f64, height: f64) -> Camera {
        let (az, el) = (azimuth.to_radians(), elevation.to_radians());
        // Viewer direction (from the object towards the eye).
        let to_eye = DVec3::new(az.sin() * el.cos(), -az.cos() * el.cos(), el.sin());
        let forward = -to_eye;
        let right = DVec3::Z.cross(to_eye).try_normalize().unwrap_or(DVec3::X);
        let up = to_eye.cross(right);
        let (min, max) =
            positions.iter().fold((DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)), |(lo, hi), &p| {
                (lo.min(p), hi.max(p))
            });
        let centre = if positions.is_empty() { DVec3::ZERO } else { (min + max) / 2.0 };
        // Extent of the projected points around the centre.
        let (mut extent_x, mut extent_y) = (0.0f64, 0.0f64);
        for &p in positions {
            let d = p - centre;
            extent_x = extent_x.max(d.dot(right).abs());
            extent_y = extent_y.max(d.dot(up).abs());
        }
        let margin = 0.92;
        let scale = if extent_x == 0.0 && extent_y == 0.0 {
            1.0
        } else {
            margin * (width / 2.0 / extent_x.max(1e-300)).min(height / 2.0 / extent_y.max(1e-300))
        };
        Camera { right, up, forward, centre, scale, half_size: DVec2::new(width / 2.0, height / 2.0) }
    }

    /// The same view for an image `factor` times larger.
    fn scaled(self, factor: f64) -> Camera {
        Camera { scale: self.scale * factor, half_size: self.half_size * factor, ..self }
    }

    fn project(&self, p: DVec3) -> DVec3 {
        let d = p - self.centre;
        DVec3::new(
            self.half_size.x + self.scale * d.dot(self.right),
            self.half_size.y - self.scale * d.dot(self.up),
            d.dot(self.forward),
        )
    }
}

/// Renders a polygon soup (faces fan-triangulated) with the camera framing its own
/// bounding box.
///
/// # Errors
/// As [`render_with_camera`].
pub fn render(soup: &PolygonSoup, options: &RenderOptions) -> CliResult<Image> {
    let camera = Camera::framing(
        &soup.positions,
        options.azimuth,
        options.elevation,
        options.width as f64,
        options.height as f64,
    );
    render_with_camera(soup, options, camera)
}

/// Renders with a given camera (so several meshes can share one view). An image above
/// [`MAX_PIXELS`], or whose buffers the allocator refuses, is an error rather than an
/// overflow or an abort.
///
/// # Errors
/// [`CliError::Input`] naming the size and the limit.
pub fn render_with_camera(soup: &PolygonSoup, options: &RenderOptions, camera: Camera) -> CliResult<Image> {
    let pixels = u64::from(options.width) * u64::from(options.height);
    if pixels > MAX_PIXELS {
        return Err(CliError::Input(format!(
            "{}x{} image: {pixels} pixels, at most {MAX_PIXELS} for the {SUPERSAMPLE}x{SUPERSAMPLE}-supersampled buffers",
            options.width, options.height
        )));
    }
    let too_large = || {
        CliError::Input(format!(
            "{}x{} image: cannot allocate its {SUPERSAMPLE}x{SUPERSAMPLE}-supersampled buffers (288 bytes per pixel)",
            options.width, options.height
        ))
    };
    // Within MAX_PIXELS the supersampled sides and count fit the u32 pixel indices.
    let (w, h) = (options.width * SUPERSAMPLE, options.height * SUPERSAMPLE);
    let count = (w * h) as usize;
    let mut colour = Vec::new();
    colour.try_reserve_exact(count).map_err(|_| too_large())?;
    colour.resize(count, background());
    let mut depth = Vec::new();
    depth.try_reserve_exact(count).map_err(|_| too_large())?;
    depth.resize(count, f64::INFINITY);
    draw(soup, options, camera, (w, h), &mut colour, &mut depth);
    Ok(downsample(&colour, options.width, options.height))
}

fn background() -> DVec3 {
    DVec3::from_array(BACKGROUND.map(|c| c as f64 / 255.0))
}

/// Rasterizes into the supersampled `w x h` buffers.
fn draw(
    soup: &PolygonSoup,
    options: &RenderOptions,
    camera: Camera,
    (w, h): (u32, u32),
    colour: &mut [DVec3],
    depth: &mut [f64],
) {
    let camera = camera.scaled(SUPERSAMPLE as f64);
    let screen: Vec<DVec3> = soup.positions.iter().map(|&p| camera.project(p)).collect();
    let vertex_normals = (options.shading == Shading::Smooth).then(|| vertex_normals(soup));
    let light = (-camera.forward + 0.6 * camera.up + 0.4 * camera.right).normalize();

    for face in soup.faces() {
        let face_normal = polygon_normal(soup, face);
        for k in 1..face.len().saturating_sub(1) {
            let corners = [face[0], face[k], face[k + 1]];
            let normals = corners.map(|v| match &vertex_normals {
                Some(n) => n[v as usize],
                None => face_normal,
            });
            raster_triangle(corners.map(|v| screen[v as usize]), normals, light, (w, h), colour, depth);
        }
    }
    if options.wireframe {
        let thickness = SUPERSAMPLE as f64 * 0.6;
        for face in soup.faces() {
            for k in 0..face.len() {
                // Interior edges are drawn from both faces; painting a pixel twice with
                // the same colour changes nothing.
                let (a, b) = (face[k], face[(k + 1) % face.len()]);
                draw_line(screen[a as usize], screen[b as usize], thickness, (w, h), colour, depth);
            }
        }
    }
}

fn polygon_normal(soup: &PolygonSoup, face: &[u32]) -> DVec3 {
    // Newell's method: robust for non-planar polygons.
    let mut n = DVec3::ZERO;
    for k in 0..face.len() {
        let p = soup.positions[face[k] as usize];
        let q = soup.positions[face[(k + 1) % face.len()] as usize];
        n += DVec3::new((p.y - q.y) * (p.z + q.z), (p.z - q.z) * (p.x + q.x), (p.x - q.x) * (p.y + q.y));
    }
    n.try_normalize().unwrap_or(DVec3::Z)
}

fn vertex_normals(soup: &PolygonSoup) -> Vec<DVec3> {
    let mut normals = vec![DVec3::ZERO; soup.positions.len()];
    for face in soup.faces() {
        let p0 = soup.positions[face[0] as usize];
        for k in 1..face.len().saturating_sub(1) {
            let (p1, p2) = (soup.positions[face[k] as usize], soup.positions[face[k + 1] as usize]);
            let area_normal = (p1 - p0).cross(p2 - p0);
            for v in [face[0], face[k], face[k + 1]] {
                normals[v as usize] += area_normal;
            }
        }
    }
    normals.into_iter().map(|n| n.try_normalize().unwrap_or(DVec3::Z)).collect()
}

fn shade(normal: DVec3, light: DVec3, front_facing: bool) -> DVec3 {
    // Two-sided lighting: back faces get their own colour, lit with the flipped normal.
    let (n, base) = if front_facing { (normal, FRONT_COLOUR) } else { (-normal, BACK_COLOUR) };
    let diffuse = n.dot(light).max(0.0);
    base * (0.35 + 0.65 * diffuse)
}

fn raster_triangle(
    p: [DVec3; 3],
    normals: [DVec3; 3],
    light: DVec3,
    (w, h): (u32, u32),
    colour: &mut [DVec3],
    depth: &mut [f64],
) {
    let area = (p[1].x - p[0].x) * (p[2].y - p[0].y) - (p[2].x - p[0].x) * (p[1].y - p[0].y);
    if area.abs() < 1e-12 {
        return;
    }
    let min_x = p.iter().map(|q| q.x).fold(f64::INFINITY, f64::min).floor().max(0.0) as u32;
    let max_x = p.iter().map(|q| q.x).fold(f64::NEG_INFINITY, f64::max).ceil().min(w as f64 - 1.0);
    let min_y = p.iter().map(|q| q.y).fold(f64::INFINITY, f64::min).floor().max(0.0) as u32;
    let max_y = p.iter().map(|q| q.y).fold(f64::NEG_INFINITY, f64::max).ceil().min(h as f64 - 1.0);
    if max_x < 0.0 || max_y < 0.0 {
        return;
    }
    // Front or back is decided by the triangle's winding on screen (y points down, so a
    // counter-clockwise face has negative signed area), not by the interpolated normals,
    // which would paint silhouettes with the back colour.
    let front_facing = area < 0.0;
    let shaded = normals.map(|n| shade(n, light, front_facing));
    for y in min_y..=max_y as u32 {
        for x in min_x..=max_x as u32 {
            let (px, py) = (x as f64 + 0.5, y as f64 + 0.5);
            let edge = |a: DVec3, b: DVec3| (b.x - a.x) * (py - a.y) - (px - a.x) * (b.y - a.y);
            let l0 = edge(p[1], p[2]) / area;
            let l1 = edge(p[2], p[0]) / area;
            let l2 = 1.0 - l0 - l1;
            if l0 < 0.0 || l1 < 0.0 || l2 < 0.0 {
                continue;
            }
            let z = l0 * p[0].z + l1 * p[1].z + l2 * p[2].z;
            let i = (y * w + x) as usize;
            if z < depth[i] {
                depth[i] = z;
                colour[i] = l0 * shaded[0] + l1 * shaded[1] + l2 * shaded[2];
            }
        }
    }
}

fn draw_line(a: DVec3, b: DVec3, thickness: f64, (w, h): (u32, u32), colour: &mut [DVec3], depth: &[f64]) {
    let length = ((b.x - a.x).powi(2) + (b.y - a.y).powi(2)).sqrt();
    let steps = (length * 2.0).ceil().max(1.0) as u32;
    let radius = (thickness / 2.0).ceil() as i64;
    for s in 0..=steps {
        let t = s as f64 / steps as f64;
        let q = a.lerp(b, t);
        for dy in -radius..=radius {
            for dx in -radius..=radius {
                let (x, y) = (q.x.floor() as i64 + dx, q.y.floor() as i64 + dy);
                if x < 0 || y < 0 || x >= w as i64 || y >= h as i64 {
                    continue;
                }
                let i = (y as u32 * w + x as u32) as usize;
                // Visible if not behind the surface by more than a small tolerance.
                let tolerance = 1e-3 * (1.0 + q.z.abs());
                if q.z <= depth[i] + tolerance || depth[i].is_infinite() {
                    colour[i] = WIRE_COLOUR;
                }
            }
        }
    }
}

fn downsample(colour: &[DVec3], width: u32, height: u32) -> Image {
    let w = width * SUPERSAMPLE;
    let mut pixels = Vec::with_capacity((width * height) as usize);
    for y in 0..height {
        for x in 0..width {
            let mut sum = DVec3::ZERO;
            for sy in 0..SUPERSAMPLE {
                for sx in 0..SUPERSAMPLE {
                    sum += colour[((y * SUPERSAMPLE + sy) * w + x * SUPERSAMPLE + sx) as usize];
                }
            }
            let c = sum / (SUPERSAMPLE * SUPERSAMPLE) as f64;
            pixels.push(c.to_array().map(|v| (v.clamp(0.0, 1.0) * 255.0).round() as u8));
        }
    }
    Image { width, height, pixels }
}

/// `multires render MESH OUT.png [--size WxH] [--wireframe] [--view az,el] [--side-by-side B ...]`.
pub fn run(args: &super::mesh_cmds::RenderArgs) -> CliResult {
    let (width, height) = parse_pair(&args.size, 'x')
        .filter(|&(w, h)| {
            (1.0..=16384.0).contains(&w) && (1.0..=16384.0).contains(&h) && w.fract() == 0.0 && h.fract() == 0.0
        })
        .ok_or_else(|| {
            CliError::Input(format!("--size {}: expected WxH with whole numbers from 1 to 16384", args.size))
        })?;
    let panels = 1 + args.side_by_side.len() as u64;
    let pixels = (width as u64) * (height as u64) * panels;
    if pixels > MAX_PIXELS {
        let across = if panels > 1 { format!(" in {panels} panels") } else { String::new() };
        return Err(CliError::Input(format!(
            "--size {}: {pixels} pixels{across}, at most {MAX_PIXELS} (e.g. 4096x2048) for the supersampled buffers",
            args.size
        )));
    }
    let (azimuth, elevation) = parse_pair(&args.view, ',')
        .filter(|&(a, e)| a.is_finite() && (-90.0..=90.0).contains(&e))
        .ok_or_else(|| {
            CliError::Input(format!(
                "--view {}: expected azimuth,elevation in degrees (elevation in -90..90)",
                args.view
            ))
        })?;
    let options = RenderOptions {
        width: width as u32,
        height: height as u32,
        azimuth,
        elevation,
        shading: if args.flat { Shading::Flat } else { Shading::Smooth },
        wireframe: args.wireframe,
    };
    let mut soups = Vec::new();
    for path in std::iter::once(&args.mesh).chain(&args.side_by_side) {
        let (soup, report) = super::common::read_soup(path)?;
        super::common::note_dropped(path, &report);
        if let Some(vertex) = soup.positions.iter().position(|p| !p.is_finite()) {
            return Err(CliError::Input(format!("{}: vertex {vertex} has a non-finite coordinate", path.display())));
        }
        soups.push(soup);
    }
    // The picture does not depend on the scale (the camera frames the bounding box):
    // meshes far from 1 are drawn at unit scale, whose normals neither underflow nor
    // overflow (a mesh at 1e-181 was drawn flat, without shading).
    let scale = mesh_topo::scale::unit_scale(soups.iter().flat_map(|soup| &soup.positions));
    if scale != 1.0 {
        soups.iter_mut().for_each(|soup| _ = mesh_topo::scale::rescale(&mut soup.positions, scale));
    }
    let image = if soups.len() == 1 {
        render(&soups[0], &options)?
    } else {
        // Side-by-side panels share one camera framing all meshes, so levels compare 1:1.
        let all: Vec<DVec3> = soups.iter().flat_map(|s| s.positions.iter().copied()).collect();
        let camera = Camera::framing(&all, azimuth, elevation, width, height);
        let panels = soups.iter().map(|soup| render_with_camera(soup, &options, camera));
        Image::side_by_side(&panels.collect::<CliResult<Vec<Image>>>()?)
    };
    image.write_png(&args.out).map_err(|source| CliError::Io { path: args.out.clone(), source })?;
    println!(
        "wrote {} ({}x{}, {:.1}% covered)",
        args.out.display(),
        image.width,
        image.height,
        100.0 * image.coverage()
    );
    Ok(())
}

fn parse_pair(text: &str, separator: char) -> Option<(f64, f64)> {
    let (a, b) = text.split_once(separator)?;
    Some((a.trim().parse().ok()?, b.trim().parse().ok()?))
}

#[cfg(test)]
mod tests {
    use super::*;
    use mesh_topo::shapes;

    #[test]
    fn cube_is_centred_lit_and_framed() {
        let options = RenderOptions { width: 120, height: 90, ..RenderOptions::default() };
        let image = render(&shapes::cube(), &options).unwrap();
        let coverage = image.coverage();
        assert!(coverage > 0.3 && coverage < 0.9, "coverage {coverage}");
        assert_eq!(image.pixel(0, 0), BACKGROUND);
        assert_eq!(image.pixel(119, 89), BACKGROUND);
        let centre = image.pixel(60, 45);
        assert_ne!(centre, BACKGROUND);
        // The front colour is bluish: blue channel dominates red.
        assert!(centre[2] > centre[0], "{centre:?}");
        // Deterministic.
        assert_eq!(render(&shapes::cube(), &options).unwrap(), image);
    }

    #[test]
    fn wireframe_adds_dark_pixels() {
        let options = RenderOptions { width: 100, height: 100, wireframe: true, ..RenderOptions::default() };
        let wired = render(&shapes::icosahedron(), &options).unwrap();
        let plain = render(&shapes::icosahedron(), &RenderOptions { wireframe: false, ..options }).unwrap();
        let brightness = |p: [u8; 3]| p.iter().map(|&c| c as u32).sum::<u32>();
        let changed: Vec<usize> = (0..wired.pixels.len()).filter(|&i| wired.pixels[i] != plain.pixels[i]).collect();
        assert!(changed.len() > 200, "{} pixels changed", changed.len());
        let darker = changed.iter().filter(|&&i| brightness(wired.pixels[i]) < brightness(plain.pixels[i])).count();
        assert!(darker * 10 >= changed.len() * 9, "{darker} of {} changed pixels are darker", changed.len());
    }

    #[test]
    fn side_by_side_concatenates() {
        let options = RenderOptions { width: 40, height: 30, ..RenderOptions::default() };
        let a = render(&shapes::cube(), &options).unwrap();
        let b = render(&shapes::tetrahedron(), &options).unwrap();
        let both = Image::side_by_side(&[a.clone(), b.clone()]);
        assert_eq!((both.width, both.height), (80, 30));
        assert_eq!(both.pixel(10, 10), a.pixel(10, 10));
        assert_eq!(both.pixel(50, 12), b.pixel(10, 12));
    }

    #[test]
    fn sizes_beyond_the_buffers_are_an_error() {
        // Used to overflow the u32 index (or abort allocating 58 GB at 16384x16384).
        for (width, height) in [(u32::MAX, 1), (1, u32::MAX), (40_000, 40_000), (16_384, 16_384), (4097, 2048)] {
            let options = RenderOptions { width, height, ..RenderOptions::default() };
            let error = render(&shapes::cube(), &options).unwrap_err().to_string();
            assert!(error.contains(&format!("{width}x{height} image")) && error.contains("at most"), "{error}");
        }
    }
}
