//! Grid voxelization (assignment 5): the occupied cells of the uniform grid
//! as opaque boxes, rendered by the ordinary renderer.
//!
//! The grid is built by the accelerator's own code ([`Grid::new`] over the
//! world's bounded primitives), so the picture shows the cells the renderer
//! walks. The view is a scene of its own: one box face (two triangles) for
//! every side of an occupied cell whose neighbour is empty, lit by the
//! scene's lights through its camera, so a ray tracing the view hits the
//! first occupied cell it enters, on the face it entered.
//!
//! Palette (the course leaves it open; the reference renders use a random
//! colour per cell): `-visualize_grid` paints every cell light grey, so the
//! shading shows the shape; `-visualize_grid_count` colours a cell by how
//! many primitives overlap it, on the ramp of [`count_color`] from 1 (dark
//! blue) to the largest count (red), with a legend drawn by [`legend`].

use super::draw::Canvas;
use crate::accel::grid::Lattice;
use crate::accel::Grid;
use crate::math::{Vec2, Vec3};
use crate::scene::{Material, Node, Phong, Scene, ShapeDesc};
use crate::world::World;

/// What the grid view colours its cells by.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GridView {
    /// Every occupied cell the same light grey.
    Occupied,
    /// Each cell by its primitive count, with a legend.
    Count,
}

/// The grid's cells and how many primitives each holds.
#[derive(Clone, Debug)]
pub struct Voxels {
    /// Where the cells are.
    pub lattice: Lattice,
    /// Primitive count per cell, in [`Lattice::linear`] order.
    pub counts: Vec<u32>,
}

/// The grid the renderer would build over `world` (`res` cells per axis, or
/// the automatic resolution), as counts per cell.
pub fn voxelize(world: &World, res: Option<[u32; 3]>) -> Voxels {
    let ids: Vec<u32> = (0..world.prims().len() as u32)
        .filter(|i| !world.unbounded().contains(i))
        .collect();
    let grid = Grid::new(world.prims(), ids, res);
    let lattice = *grid.lattice();
    let mut counts = vec![0; lattice.cells()];
    for c in cells(&lattice) {
        counts[lattice.linear(c)] = grid.cell_items(c).len() as u32;
    }
    Voxels { lattice, counts }
}

/// Every cell index of `l`, x fastest.
pub fn cells(l: &Lattice) -> impl Iterator<Item = [u32; 3]> {
    let [nx, ny, nz] = l.res;
    (0..nz).flat_map(move |z| (0..ny).flat_map(move |y| (0..nx).map(move |x| [x, y, z])))
}

impl Voxels {
    /// Primitives overlapping cell `c`; 0 outside the grid.
    pub fn count(&self, c: [i64; 3]) -> u32 {
        let r = self.lattice.res;
        if (0..3).any(|a| c[a] < 0 || c[a] >= r[a] as i64) {
            return 0;
        }
        self.counts[self.lattice.linear([c[0] as u32, c[1] as u32, c[2] as u32])]
    }

    /// The occupied cells.
    pub fn occupied(&self) -> Vec<[u32; 3]> {
        cells(&self.lattice)
            .filter(|&c| self.counts[self.lattice.linear(c)] > 0)
            .collect()
    }

    /// The largest count of any cell.
    pub fn max_count(&self) -> u32 {
        self.counts.iter().copied().max().unwrap_or(0)
    }

    /// `scene` with its objects replaced by the occupied cells' visible
    /// faces (camera, lights and background kept).
    pub fn scene(&self, scene: &Scene, view: GridView) -> Scene {
        let max = self.max_count().max(1);
        let materials: Vec<Material> = match view {
            GridView::Occupied => vec![phong(Vec3::splat(0.85))],
            GridView::Count => (1..=max).map(|n| phong(count_color(n, max))).collect(),
        };
        let mut faces = Vec::new();
        for c in self.occupied() {
            let n = self.count(c.map(i64::from));
            let material = match view {
                GridView::Occupied => 0,
                GridView::Count => n as usize - 1,
            };
            let b = self.lattice.cell_bounds(c);
            for axis in 0..3 {
                for up in [false, true] {
                    let mut next = c.map(i64::from);
                    next[axis] += if up { 1 } else { -1 };
                    if self.count(next) > 0 {
                        continue; // shared with an occupied neighbour: never seen
                    }
                    for tri in face(b.min, b.max, axis, up) {
                        faces.push(Node::Shape {
                            shape: ShapeDesc::Triangle(tri.map(|p| p.as_dvec3())),
                            material: Some(material),
                        });
                    }
                }
            }
        }
        Scene {
            camera: scene.camera.clone(),
            lights: scene.lights.clone(),
            background: scene.background.clone(),
            materials,
            root: Node::Group(faces),
            effects: Default::default(),
        }
    }
}

fn phong(diffuse: Vec3) -> Material {
    Material::Phong(Phong {
        diffuse,
        ..Phong::default()
    })
}

/// The two triangles of the box face on the `up` (max) or min side of
/// `axis`, wound counter-clockwise seen from outside so their front faces out.
fn face(lo: Vec3, hi: Vec3, axis: usize, up: bool) -> [[Vec3; 3]; 2] {
    let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
    let corner = |du: bool, dv: bool| {
        let mut p = lo;
        p[axis] = if up { hi[axis] } else { lo[axis] };
        p[u] = if du { hi[u] } else { lo[u] };
        p[v] = if dv { hi[v] } else { lo[v] };
        p
    };
    // e_u × e_v = e_axis, so (00, 10, 11) turns counter-clockwise about +axis.
    let (p0, p1, p2, p3) = (
        corner(false, false),
        corner(true, false),
        corner(true, true),
        corner(false, true),
    );
    if up {
        [[p0, p1, p2], [p0, p2, p3]]
    } else {
        [[p0, p2, p1], [p0, p3, p2]]
    }
}

/// The colour of a cell holding `n` of at most `max` primitives: a ramp
/// through dark blue, cyan, green, yellow and red (1 = dark blue, `max` =
/// red), on a logarithmic scale when counts span more than a factor of 16.
pub fn count_color(n: u32, max: u32) -> Vec3 {
    let x = if max <= 1 {
        0.0
    } else if max > 16 {
        (n.max(1) as f32).ln() / (max as f32).ln()
    } else {
        (n.max(1) - 1) as f32 / (max - 1) as f32
    };
    ramp(x)
}

/// The heat ramp shared by every heat map: `x` in `[0, 1]`.
pub fn ramp(x: f32) -> Vec3 {
    const STOPS: [Vec3; 5] = [
        Vec3::new(0.05, 0.05, 0.5),
        Vec3::new(0.0, 0.7, 0.9),
        Vec3::new(0.1, 0.8, 0.1),
        Vec3::new(0.95, 0.9, 0.1),
        Vec3::new(0.9, 0.1, 0.05),
    ];
    let x = x.clamp(0.0, 1.0) * (STOPS.len() - 1) as f32;
    let i = (x.floor() as usize).min(STOPS.len() - 2);
    STOPS[i].lerp(STOPS[i + 1], x - i as f32)
}

/// Draws a vertical colour bar for counts 1..=`max` at the right edge of
/// `canvas`, labelled with 1 at the bottom and `max` at the top.
pub fn legend(canvas: &mut Canvas, max: u32) {
    let (w, h) = (canvas.width as i64, canvas.height as i64);
    let bar_h = (h * 2 / 3).max(8);
    let (x0, y0) = (w - 10, (h - bar_h) / 2);
    for k in 0..bar_h {
        let frac = 1.0 - k as f32 / (bar_h - 1).max(1) as f32;
        let n = 1 + (frac * (max.max(1) - 1) as f32).round() as u32;
        let c = count_color(n, max.max(1));
        for x in x0..x0 + 6 {
            canvas.put(x, y0 + k, c);
        }
    }
    let scale = 1;
    let top = max.to_string();
    let tw = super::draw::text_width(&top, scale) as f32;
    canvas.text(
        Vec2::new(w as f32 - 12.0 - tw, (h - y0) as f32 - 5.0),
        &top,
        Vec3::ONE,
        scale,
    );
    canvas.text(
        Vec2::new(
            w as f32 - 12.0 - super::draw::text_width("1", scale) as f32,
            (h - y0 - bar_h) as f32 + 1.0,
        ),
        "1",
        Vec3::ONE,
        scale,
    );
}
