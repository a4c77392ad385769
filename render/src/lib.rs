//! # isolab-render
//!
//! Pictures of meshes for the `isolab render` command and the report: a fixed perspective
//! camera, flat or smooth (Gouraud-interpolated normal) shading with a headlight plus a key
//! light, an optional wireframe overlay, 2x supersampling, rasterized by the `euc` crate. Also turntable GIFs and side-by-side pairs.
//!
//! The wireframe is drawn in the fragment shader: each corner carries its distance to the opposite
//! edge in pixels, interpolation gives every fragment its distance to the three edges, and
//! fragments closer than the line half-width take the wire colour.

use euc::{buffer::Buffer2d, rasterizer, Pipeline};
use glam::{Mat4, Vec3, Vec4};
use isolab_algorithms::TriMesh;
use std::path::Path;

/// Shading of the faces.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Shading {
    /// One normal per triangle: shows every facet.
    Flat,
    /// Vertex normals interpolated across triangles (the mesh's own, or area-weighted).
    Smooth,
}

/// How to draw a mesh.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RenderOptions {
    /// Output width in pixels.
    pub width: u32,
    /// Output height in pixels.
    pub height: u32,
    /// Face shading.
    pub shading: Shading,
    /// Draw triangle edges.
    pub wireframe: bool,
    /// Direction from the mesh toward the camera.
    pub view: Vec3,
    /// Rotation of the mesh about the vertical (y) axis, radians (turntables).
    pub spin: f32,
    /// Surface colour, linear RGB in [0, 1].
    pub color: [f32; 3],
}

impl Default for RenderOptions {
    fn default() -> Self {
        Self {
            width: 480,
            height: 480,
            shading: Shading::Flat,
            wireframe: false,
            view: Vec3::new(1.0, 0.75, 1.35),
            spin: 0.0,
            color: [0.85, 0.62, 0.32],
        }
    }
}

/// An RGB image, rows top to bottom.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `width * height * 3` bytes.
    pub rgb: Vec<u8>,
}

const BACKGROUND: [f32; 3] = [0.97, 0.97, 0.96];
const WIRE: [f32; 3] = [0.12, 0.12, 0.14];
const SUPERSAMPLE: u32 = 2;

struct Surface<'a> {
    clip: &'a [[f32; 4]],
    normals: &'a [Vec3],
    /// Per-corner colours, or empty for `color` everywhere.
    colours: &'a [Vec3],
    edge_px: &'a [Vec3],
    color: Vec3,
    lights: [Vec3; 2],
    wire_px: f32,
}

impl Pipeline for Surface<'_> {
    type Vertex = u32;
    type VsOut = (vek::Vec3<f32>, vek::Vec3<f32>, vek::Vec3<f32>);
    type Pixel = u32;

    fn vert(&self, v: &u32) -> ([f32; 4], Self::VsOut) {
        let i = *v as usize;
        let n = self.normals[i];
        let e = self.edge_px[i];
        let c = self.colours.get(i).copied().unwrap_or(self.color);
        (self.clip[i], (vek::Vec3::new(n.x, n.y, n.z), vek::Vec3::new(e.x, e.y, e.z), vek::Vec3::new(c.x, c.y, c.z)))
    }

    fn frag(&self, (n, e, c): &Self::VsOut) -> u32 {
        if self.wire_px > 0.0 && e.x.min(e.y).min(e.z) < self.wire_px {
            return pack(Vec3::from(WIRE));
        }
        let n = Vec3::new(n.x, n.y, n.z).normalize_or_zero();
        let diffuse: f32 = self.lights.iter().zip([0.55, 0.35]).map(|(l, w)| w * n.dot(*l).abs()).sum();
        pack(Vec3::new(c.x, c.y, c.z) * (0.22 + diffuse))
    }
}

fn pack(c: Vec3) -> u32 {
    let c = c.clamp(Vec3::ZERO, Vec3::ONE) * 255.0;
    (c.x as u32) << 16 | (c.y as u32) << 8 | c.z as u32
}

/// Renders `mesh` into an image.
pub fn render(mesh: &TriMesh, opts: &RenderOptions) -> Image {
    render_coloured(mesh, &[], opts)
}

/// Renders `mesh` with a colour per vertex (sRGB bytes, e.g. [`isolab_algorithms::materials::colour`]);
/// an empty or short slice falls back to the options' colour.
pub fn render_coloured(mesh: &TriMesh, vertex_colours: &[[u8; 3]], opts: &RenderOptions) -> Image {
    let use_colours = vertex_colours.len() == mesh.positions.len() && !vertex_colours.is_empty();
    let (w, h) = ((opts.width * SUPERSAMPLE) as usize, (opts.height * SUPERSAMPLE) as usize);
    let mut color = Buffer2d::new([w, h], pack(Vec3::from(BACKGROUND)));
    let mut depth = Buffer2d::new([w, h], 1.0f32);
    if !mesh.triangles.is_empty() {
        let (mvp, forward) = camera(mesh, opts, w as f32 / h as f32);
        let rotation = Mat4::from_rotation_y(opts.spin);
        let smooth_normals = match opts.shading {
            Shading::Smooth if mesh.normals.len() == mesh.positions.len() => mesh.normals.clone(),
            Shading::Smooth => {
                let mut m = mesh.clone();
                m.compute_face_weighted_normals();
                m.normals
            }
            Shading::Flat => Vec::new(),
        };
        // Corners are drawn as separate vertices so flat normals and edge distances can differ
        // per triangle.
        let corners = mesh.triangles.len() * 3;
        let mut clip = Vec::with_capacity(corners);
        let mut normals = Vec::with_capacity(corners);
        let mut edge_px = Vec::with_capacity(corners);
        let mut colours = Vec::with_capacity(if use_colours { corners } else { 0 });
        for t in &mesh.triangles {
            if use_colours {
                colours.extend(t.map(|i| Vec3::from(vertex_colours[i as usize].map(|c| f32::from(c) / 255.0))));
            }
            let p = t.map(|i| rotation.transform_point3(mesh.positions[i as usize]));
            let c = p.map(|q| mvp * q.extend(1.0));
            let screen = c.map(|v: Vec4| glam::Vec2::new((v.x / v.w + 1.0) * 0.5 * w as f32, (v.y / v.w + 1.0) * 0.5 * h as f32));
            let area2 = (screen[1] - screen[0]).perp_dot(screen[2] - screen[0]).abs();
            let face_n = (p[1] - p[0]).cross(p[2] - p[0]).normalize_or_zero();
            for k in 0..3 {
                let opposite = (screen[(k + 2) % 3] - screen[(k + 1) % 3]).length().max(1e-6);
                let mut e = Vec3::ZERO;
                e[k] = area2 / opposite;
                clip.push(c[k].to_array());
                edge_px.push(e);
                normals.push(match opts.shading {
                    Shading::Flat => face_n,
                    Shading::Smooth => rotation.transform_vector3(smooth_normals[t[k] as usize]),
                });
            }
        }
        let lights = [-forward, (Vec3::new(-0.6, 1.0, 0.3) - forward).normalize()];
        let surface = Surface {
            clip: &clip,
            normals: &normals,
            colours: &colours,
            edge_px: &edge_px,
            color: Vec3::from(opts.color),
            lights,
            wire_px: if opts.wireframe { 0.55 * SUPERSAMPLE as f32 } else { 0.0 },
        };
        let order: Vec<u32> = (0..corners as u32).collect();
        surface.draw::<rasterizer::Triangles<_, rasterizer::BackfaceCullingDisabled>, _>(&order, &mut color, Some(&mut depth));
    }
    downsample(&color, opts.width, opts.height)
}

/// View-projection matrix fitting the mesh's bounding sphere, and the camera's forward direction.
fn camera(mesh: &TriMesh, opts: &RenderOptions, aspect: f32) -> (Mat4, Vec3) {
    let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
    for p in &mesh.positions {
        if p.is_finite() {
            lo = lo.min(*p);
            hi = hi.max(*p);
        }
    }
    let centre = (lo + hi) * 0.5;
    let radius = ((hi - lo).length() * 0.5).max(1e-6);
    let fov = 30f32.to_radians();
    let distance = radius / (fov * 0.5).sin() * 1.02;
    let dir = opts.view.normalize_or(Vec3::Z);
    let eye = centre + dir * distance;
    let view = Mat4::look_at_rh(eye, centre, Vec3::Y);
    let proj = Mat4::perspective_rh_gl(fov, aspect, distance * 0.05, distance * 3.0);
    (proj * view, -dir)
}

fn downsample(buffer: &Buffer2d<u32>, width: u32, height: u32) -> Image {
    let s = SUPERSAMPLE as usize;
    let bw = width as usize * s;
    let raw: &[u32] = buffer.as_ref();
    let mut rgb = Vec::with_capacity(width as usize * height as usize * 3);
    for y in 0..height as usize {
        for x in 0..width as usize {
            let mut acc = [0u32; 3];
            for dy in 0..s {
                for dx in 0..s {
                    let sy = y * s + dy;
                    let p = raw[sy * bw + x * s + dx];
                    acc[0] += p >> 16 & 0xff;
                    acc[1] += p >> 8 & 0xff;
                    acc[2] += p & 0xff;
                }
            }
            rgb.extend(acc.map(|v| (v / (s * s) as u32) as u8));
        }
    }
    Image { width, height, rgb }
}

/// Two images next to each other, with a 4-pixel gap.
pub fn side_by_side(left: &Image, right: &Image) -> Image {
    let gap = 4;
    let width = left.width + gap + right.width;
    let height = left.height.max(right.height);
    let mut rgb = vec![255u8; (width * height * 3) as usize];
    for (img, x0) in [(left, 0), (right, left.width + gap)] {
        for y in 0..img.height {
            let src = &img.rgb[(y * img.width * 3) as usize..((y + 1) * img.width * 3) as usize];
            let at = ((y * width + x0) * 3) as usize;
            rgb[at..at + src.len()].copy_from_slice(src);
        }
    }
    Image { width, height, rgb }
}

/// Images in rows of `columns`, left to right then top to bottom, 4-pixel gaps, white background.
pub fn grid(images: &[&Image], columns: usize) -> Image {
    let gap = 4;
    let columns = columns.max(1);
    let rows = images.len().div_ceil(columns);
    let cell_w = images.iter().map(|i| i.width).max().unwrap_or(0);
    let cell_h = images.iter().map(|i| i.height).max().unwrap_or(0);
    let used_columns = columns.min(images.len()) as u32;
    let width = (used_columns * cell_w + used_columns.saturating_sub(1) * gap).max(1);
    let height = (rows as u32 * cell_h + (rows as u32).saturating_sub(1) * gap).max(1);
    let mut rgb = vec![255u8; (width * height * 3) as usize];
    for (k, img) in images.iter().enumerate() {
        let (x0, y0) = ((k % columns) as u32 * (cell_w + gap), (k / columns) as u32 * (cell_h + gap));
        for y in 0..img.height {
            let src = &img.rgb[(y * img.width * 3) as usize..((y + 1) * img.width * 3) as usize];
            let at = (((y0 + y) * width + x0) * 3) as usize;
            rgb[at..at + src.len()].copy_from_slice(src);
        }
    }
    Image { width, height, rgb }
}

/// Writes a PNG atomically.
pub fn save_png(path: &Path, image: &Image) -> Result<(), isolab_io::IoError> {
    isolab_io::write_atomic(path, |w| {
        let mut encoder = png::Encoder::new(w, image.width, image.height);
        encoder.set_color(png::ColorType::Rgb);
        encoder.set_depth(png::BitDepth::Eight);
        let mut writer = encoder.write_header().map_err(std::io::Error::other)?;
        writer.write_image_data(&image.rgb).map_err(std::io::Error::other)?;
        writer.finish().map_err(std::io::Error::other)
    })
}

/// Writes a turntable GIF: `frames` views a full turn apart, `delay_cs` hundredths of a second each.
pub fn save_turntable(
    path: &Path,
    mesh: &TriMesh,
    opts: &RenderOptions,
    frames: u32,
    delay_cs: u16,
) -> Result<(), isolab_io::IoError> {
    let images: Vec<Image> = (0..frames)
        .map(|k| render(mesh, &RenderOptions { spin: k as f32 / frames as f32 * std::f32::consts::TAU, ..*opts }))
        .collect();
    save_gif(path, &images, delay_cs)
}

/// Writes frames (all of the first frame's size) as a looping GIF, `delay_cs` hundredths of a
/// second each, atomically.
pub fn save_gif(path: &Path, images: &[Image], delay_cs: u16) -> Result<(), isolab_io::IoError> {
    let (width, height) = images.first().map_or((1, 1), |i| (i.width as u16, i.height as u16));
    isolab_io::write_atomic(path, |w| {
        let mut encoder = gif::Encoder::new(w, width, height, &[]).map_err(std::io::Error::other)?;
        encoder.set_repeat(gif::Repeat::Infinite).map_err(std::io::Error::other)?;
        for img in images {
            let mut frame = gif::Frame::from_rgb_speed(img.width as u16, img.height as u16, &img.rgb, 10);
            frame.delay = delay_cs;
            encoder.write_frame(&frame).map_err(std::io::Error::other)?;
        }
        Ok(())
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tetra() -> TriMesh {
        TriMesh::unit_tetrahedron()
    }

    #[test]
    fn renders_the_mesh_over_the_background() {
        let img = render(&tetra(), &RenderOptions { width: 64, height: 64, wireframe: true, ..Default::default() });
        assert_eq!(img.rgb.len(), 64 * 64 * 3);
        let bg = BACKGROUND.map(|c| (c * 255.0) as u8);
        let covered = img.rgb.chunks(3).filter(|p| p != &bg).count();
        assert!(covered > 400 && covered < 64 * 64, "{covered} pixels drawn");
        // The centre pixel shows the mesh, the corner shows the background.
        let px = |x: usize, y: usize| &img.rgb[(y * 64 + x) * 3..(y * 64 + x) * 3 + 3];
        assert_ne!(px(32, 32), bg);
        assert_eq!(px(0, 0), bg);
        let empty = render(&TriMesh::default(), &RenderOptions { width: 8, height: 8, ..Default::default() });
        assert!(empty.rgb.chunks(3).all(|p| p == bg));
    }

    #[test]
    fn grid_places_images_in_rows_of_equal_cells() {
        let a = Image { width: 2, height: 1, rgb: vec![1; 6] };
        let b = Image { width: 1, height: 2, rgb: vec![2; 6] };
        let g = grid(&[&a, &b, &a], 2);
        // Cells are 2x2 with 4-pixel gaps: two columns, two rows.
        assert_eq!((g.width, g.height), (8, 8));
        let px = |x: u32, y: u32| &g.rgb[((y * 8 + x) * 3) as usize..((y * 8 + x) * 3 + 3) as usize];
        assert_eq!(px(0, 0), &[1, 1, 1]);
        assert_eq!(px(6, 1), &[2, 2, 2]);
        assert_eq!(px(1, 6), &[1, 1, 1]);
        assert_eq!(px(7, 7), &[255, 255, 255]);
    }

    #[test]
    fn side_by_side_puts_images_next_to_each_other() {
        let a = Image { width: 2, height: 1, rgb: vec![1; 6] };
        let b = Image { width: 1, height: 2, rgb: vec![2; 6] };
        let c = side_by_side(&a, &b);
        assert_eq!((c.width, c.height), (7, 2));
        assert_eq!(&c.rgb[0..3], &[1, 1, 1]);
        assert_eq!(&c.rgb[18..21], &[2, 2, 2]);
    }
}
