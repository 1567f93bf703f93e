//! A side view of the pile as an SVG picture: every body's outline (the 2D convex hull of its
//! world-space vertices projected onto the x–y plane, seen from +z with y up), filled by mesh
//! kind and shaded by depth (nearer: darker) and drawn far to near; the box (the pieces beside
//! and under the bodies filled grey, the walls in front of and behind them as outlines); and
//! every contact point of every touching pair (a red dot with a short line along its normal).
use std::error::Error;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use bevy_ecs::prelude::*;
use bevy_ecs::system::RunSystemOnce;
use plotters::prelude::*;
use stochastic_collision::prelude::*;

use super::BodyKinds;

/// Fill of the contact dots (nothing else in the picture has it).
pub const CONTACT_COLOR: RGBColor = RGBColor(220, 20, 30);
/// Stroke of the bodies' outlines (nothing else in the picture has it).
pub const OUTLINE_COLOR: RGBColor = RGBColor(30, 30, 60);
/// Colour of the contact normals.
const NORMAL_COLOR: RGBColor = RGBColor(255, 150, 0);
/// Fill and outline of the box pieces beside or under the bodies.
const BOX_FILL: RGBColor = RGBColor(200, 200, 200);
const BOX_OUTLINE: RGBColor = RGBColor(110, 110, 110);
/// Outline of the box pieces in front of or behind the bodies.
const GLASS_OUTLINE: RGBColor = RGBColor(150, 150, 150);
/// Fill of the bodies by mesh kind (in [`BodyKinds`] order; grey for other meshes).
const KIND_COLORS: [RGBColor; 4] = [
    RGBColor(40, 110, 200),
    RGBColor(40, 160, 80),
    RGBColor(200, 130, 30),
    RGBColor(140, 70, 170),
];
const OTHER_KIND: RGBColor = RGBColor(120, 120, 120);
/// Length of the drawn normals, m.
const NORMAL_LENGTH: f64 = 0.08;
/// Picture width and the title's height, pixels.
const WIDTH: u32 = 1100;
const TITLE: u32 = 50;
/// Margin around the chart and its label areas (bottom, left), pixels.
const MARGIN: u32 = 10;
const X_LABELS: u32 = 35;
const Y_LABELS: u32 = 50;

/// What a picture shows.
#[derive(Debug, Clone, PartialEq)]
pub struct Picture {
    /// Where it was written.
    pub path: PathBuf,
    /// Bodies drawn (colliders with a `BodyVelocity`).
    pub bodies: usize,
    /// Box pieces drawn (the other colliders).
    pub box_pieces: usize,
    /// Contact points marked.
    pub contacts: usize,
    /// Touching pairs they belong to.
    pub touching_pairs: usize,
}

/// A collider projected into the picture.
struct Shape {
    /// Convex hull of its projected vertices, counter-clockwise.
    hull: Vec<(f64, f64)>,
    /// Its world z range (the depth: the viewer is at +z).
    z: (f32, f32),
    /// Its mesh kind (index into [`BodyKinds`]), if listed.
    kind: Option<usize>,
}

/// Writes the side view of `world` (the pile scene, after some updates) to `path`, creating
/// its directory if missing.
pub fn side_view(world: &mut World, path: &Path) -> Result<Picture, String> {
    let (bodies, pieces) = shapes(world);
    let (contacts, touching_pairs) = world
        .run_system_once(|pairs: CollisionPairs| {
            let touching: Vec<_> = pairs.iter().filter(|p| p.touching()).collect();
            let contacts: Vec<ContactPointXy> = touching
                .iter()
                .flat_map(|p| p.contacts())
                .map(|c| ContactPointXy {
                    point: (f64::from(c.point.x), f64::from(c.point.y)),
                    normal: (f64::from(c.normal.x), f64::from(c.normal.y)),
                })
                .collect();
            (contacts, touching.len())
        })
        .map_err(|e| format!("cannot read the collision pairs: {e}"))?;
    let names: Vec<&str> = world
        .get_resource::<BodyKinds>()
        .map(|k| k.0.iter().map(|(name, _)| *name).collect())
        .unwrap_or_default();
    let mut svg = String::new();
    draw(&mut svg, &bodies, &pieces, &contacts, &names)
        .map_err(|e| format!("cannot draw {}: {e}", path.display()))?;
    let path = super::super::write_svg(path, &svg)?;
    Ok(Picture {
        path,
        bodies: bodies.len(),
        box_pieces: pieces.len(),
        contacts: contacts.len(),
        touching_pairs,
    })
}

/// A contact point and its normal, projected.
struct ContactPointXy {
    point: (f64, f64),
    normal: (f64, f64),
}

/// The bodies and the box pieces, projected.
fn shapes(world: &mut World) -> (Vec<Shape>, Vec<Shape>) {
    let kinds: Vec<MeshCollider> = world
        .get_resource::<BodyKinds>()
        .map(|k| k.0.iter().map(|(_, c)| c.clone()).collect())
        .unwrap_or_default();
    let mut q = world.query::<(
        Entity,
        &MeshCollider,
        &ColliderPose,
        &ColliderScale,
        Has<BodyVelocity>,
    )>();
    let mut found: Vec<_> = q.iter(world).collect();
    found.sort_by_key(|(e, ..)| *e);
    let (mut bodies, mut pieces) = (Vec::new(), Vec::new());
    for (_, collider, pose, scale, is_body) in found {
        let mut z = (f32::INFINITY, f32::NEG_INFINITY);
        let points: Vec<(f64, f64)> = collider
            .collision_mesh()
            .mesh()
            .positions()
            .iter()
            .map(|&p| {
                let w = pose.0.transform_point(scale.0 * p);
                z = (z.0.min(w.z), z.1.max(w.z));
                (f64::from(w.x), f64::from(w.y))
            })
            .collect();
        let kind = kinds
            .iter()
            .position(|k| Arc::ptr_eq(k.tree(), collider.tree()));
        let shape = Shape {
            hull: convex_hull(points),
            z,
            kind,
        };
        if is_body {
            bodies.push(shape);
        } else {
            pieces.push(shape);
        }
    }
    (bodies, pieces)
}

/// The convex hull of `points`, counter-clockwise (Andrew's monotone chain).
fn convex_hull(mut points: Vec<(f64, f64)>) -> Vec<(f64, f64)> {
    points.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
    points.dedup();
    if points.len() < 3 {
        return points;
    }
    // Whether `b` turns left of the line from `o` through `a`.
    let left = |o: (f64, f64), a: (f64, f64), b: (f64, f64)| {
        (a.0 - o.0) * (b.1 - o.1) - (a.1 - o.1) * (b.0 - o.0) > 0.0
    };
    let mut hull: Vec<(f64, f64)> = Vec::with_capacity(points.len() + 1);
    // The lower chain left to right.
    for &p in &points {
        while hull.len() >= 2 && !left(hull[hull.len() - 2], hull[hull.len() - 1], p) {
            hull.pop();
        }
        hull.push(p);
    }
    // The upper chain right to left, from the lower chain's last point.
    let lower = hull.len();
    for &p in points.iter().rev().skip(1) {
        while hull.len() > lower && !left(hull[hull.len() - 2], hull[hull.len() - 1], p) {
            hull.pop();
        }
        hull.push(p);
    }
    // The upper chain ends at the first point.
    hull.pop();
    hull
}

/// `color` drawn towards white by `amount` (0: unchanged, 1: white).
fn lighten(color: RGBColor, amount: f64) -> RGBColor {
    let mix = |c: u8| (f64::from(c) + (255.0 - f64::from(c)) * amount).round() as u8;
    RGBColor(mix(color.0), mix(color.1), mix(color.2))
}

/// Draws the picture into `svg`.
fn draw(
    svg: &mut String,
    bodies: &[Shape],
    pieces: &[Shape],
    contacts: &[ContactPointXy],
    names: &[&str],
) -> Result<(), Box<dyn Error>> {
    // The world rectangle shown: everything drawn, with a little room.
    let (mut x0, mut x1, mut y0, mut y1) = (
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
    );
    let all = bodies.iter().chain(pieces).flat_map(|s| &s.hull);
    for &(x, y) in all.chain(contacts.iter().map(|c| &c.point)) {
        (x0, x1, y0, y1) = (x0.min(x), x1.max(x), y0.min(y), y1.max(y));
    }
    if !(x0 < x1 && y0 < y1) {
        (x0, x1, y0, y1) = (-1.0, 1.0, -1.0, 1.0);
    }
    let pad = 0.03 * (x1 - x0).max(y1 - y0);
    (x0, x1, y0, y1) = (x0 - pad, x1 + pad, y0 - pad, y1 + pad);
    // One scale for both axes: the picture's height follows the scene's aspect, and the
    // shorter side of the rectangle grows to fill the plot.
    let plot_w = f64::from(WIDTH - 2 * MARGIN - Y_LABELS);
    let plot_h = (plot_w * (y1 - y0) / (x1 - x0)).clamp(250.0, 1400.0);
    let height = TITLE + 2 * MARGIN + X_LABELS + plot_h.round() as u32;
    let scale = (plot_w / (x1 - x0)).min(plot_h / (y1 - y0));
    let grow = |lo: f64, hi: f64, pixels: f64| {
        let extra = (pixels / scale - (hi - lo)) / 2.0;
        (lo - extra)..(hi + extra)
    };
    let (xs, ys) = (grow(x0, x1, plot_w), grow(y0, y1, plot_h));

    let root = SVGBackend::with_string(svg, (WIDTH, height)).into_drawing_area();
    root.fill(&WHITE)?;
    let (title, area) = root.split_vertically(TITLE);
    let kinds = if names.is_empty() {
        String::new()
    } else {
        let listed: Vec<String> = names
            .iter()
            .take(KIND_COLORS.len())
            .zip(["blue", "green", "orange", "purple"])
            .map(|(name, colour)| format!("{name} {colour}"))
            .collect();
        format!(" ({})", listed.join(", "))
    };
    title.draw_text(
        &format!(
            "pile seen from the side (from +z, y up): {} bodies{kinds}, nearer darker",
            bodies.len()
        ),
        &("sans-serif", 17).into_font().color(&BLACK),
        (MARGIN as i32 + 5, 6),
    )?;
    title.draw_text(
        &format!(
            "{} contact points of the touching pairs (red dots, orange: normal); grey: the box \
             (lines: its front and back walls)",
            contacts.len()
        ),
        &("sans-serif", 14).into_font().color(&RGBColor(60, 60, 60)),
        (MARGIN as i32 + 5, 28),
    )?;
    let mut chart = ChartBuilder::on(&area)
        .margin(MARGIN)
        .x_label_area_size(X_LABELS)
        .y_label_area_size(Y_LABELS)
        .build_cartesian_2d(xs, ys)?;
    chart
        .configure_mesh()
        .disable_mesh()
        .x_desc("x (m)")
        .y_desc("y (m)")
        .draw()?;

    // The box: the pieces whose depth range spans the middle of the bodies' are beside or
    // under them (filled); the others are in front of or behind them (outlines, not to hide
    // the pile).
    let depth = bodies
        .iter()
        .fold((f32::INFINITY, f32::NEG_INFINITY), |d, s| {
            (d.0.min(s.z.0), d.1.max(s.z.1))
        });
    let middle = if bodies.is_empty() {
        0.0
    } else {
        0.5 * (depth.0 + depth.1)
    };
    let beside = |s: &Shape| s.z.0 <= middle && middle <= s.z.1;
    let closed = |s: &Shape| {
        s.hull
            .iter()
            .chain(s.hull.first())
            .copied()
            .collect::<Vec<_>>()
    };
    for s in pieces.iter().filter(|s| !beside(s)) {
        chart.draw_series([PathElement::new(closed(s), GLASS_OUTLINE.stroke_width(1))])?;
    }
    for s in pieces.iter().filter(|s| beside(s)) {
        chart.draw_series([Polygon::new(s.hull.clone(), BOX_FILL.filled())])?;
        chart.draw_series([PathElement::new(closed(s), BOX_OUTLINE.stroke_width(1))])?;
    }

    // The bodies, far to near, each over the ones behind it.
    let mut order: Vec<&Shape> = bodies.iter().collect();
    let centre = |s: &Shape| 0.5 * (s.z.0 + s.z.1);
    order.sort_by(|a, b| centre(a).total_cmp(&centre(b)));
    let span = (depth.1 - depth.0).max(1e-6);
    for s in order {
        let far = f64::from((depth.1 - centre(s)) / span).clamp(0.0, 1.0);
        let base = s
            .kind
            .and_then(|k| KIND_COLORS.get(k).copied())
            .unwrap_or(OTHER_KIND);
        let fill = lighten(base, 0.15 + 0.6 * far);
        chart.draw_series([Polygon::new(s.hull.clone(), fill.filled())])?;
        chart.draw_series([PathElement::new(closed(s), OUTLINE_COLOR.stroke_width(1))])?;
    }

    // The contacts: the normals first, then the dots over them.
    chart.draw_series(contacts.iter().map(|c| {
        let (x, y) = c.point;
        let (nx, ny) = c.normal;
        PathElement::new(
            vec![(x, y), (x + nx * NORMAL_LENGTH, y + ny * NORMAL_LENGTH)],
            NORMAL_COLOR.stroke_width(1),
        )
    }))?;
    chart.draw_series(
        contacts
            .iter()
            .map(|c| Circle::new(c.point, 2, CONTACT_COLOR.filled())),
    )?;
    root.present()?;
    Ok(())
}
