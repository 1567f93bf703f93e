//! Continuous tracking: the neighbourhoods of the kept feature pairs checked over the step, so
//! that surfaces passing through each other between two frames are caught.
//!
//! Each feature pair kept from the last step marks a place where the two surfaces were close.
//! Around it, the triangles within a few vertex rings on each side (more rings the farther the
//! pair's features moved, so that where the surfaces meet is still inside) are swept from their
//! positions at the start of the step to those at its end (each vertex on a straight line, in
//! the first mesh's frame), the pairs whose swept boxes meet are decided by the exact
//! continuous primitives of [`crate::ccd`] (three vertex–face tests each way, nine edge–edge
//! tests), and the earliest time at which they touch is the pair's time of impact.
use rustc_hash::FxHashSet as HashSet;

use glam::DVec3;

use super::contact::Contact;
use super::feature::Feature;
use super::surface::TrackedSurface;
use crate::ccd::window::{MovingBox, overlap_window};
use crate::ccd::{CcdScratch, PrimitiveTolerances, Trajectory, edge_edge_time, vertex_face_time};
use crate::geometry::{PoseF64, closest_points_triangle_triangle};

/// Vertex rings walked around a kept pair's features when they did not move; each mean edge
/// length the features moved adds one, up to [`MAX_SWEEP_RINGS`].
pub(crate) const BASE_SWEEP_RINGS: u32 = 1;

/// The most vertex rings walked around a kept pair's features: a crossing farther than this
/// from every kept pair along the surface is not seen.
pub const MAX_SWEEP_RINGS: u32 = 8;

/// Features closer than this fraction of the surfaces' size (in every coordinate) touch.
const SWEEP_DISTANCE: f64 = 1e-7;

/// One side of a tracked pair over the step, in the first mesh's frame: the vertices start at
/// the surface's previous positions if it `deformed` since the tracker's last step (else at
/// their current ones) placed by `start_pose`, and end at the current positions placed by
/// `end_pose` (`None`: the mesh's own frame).
#[derive(Clone, Copy)]
pub(crate) struct SweptSide<'a> {
    pub surface: &'a TrackedSurface,
    pub deformed: bool,
    pub start_pose: Option<PoseF64>,
    pub end_pose: Option<PoseF64>,
}

fn placed(pose: &Option<PoseF64>, p: glam::Vec3) -> DVec3 {
    match pose {
        None => p.as_dvec3(),
        Some(pose) => pose.transform_point(p),
    }
}

impl SweptSide<'_> {
    fn start(&self, v: u32) -> DVec3 {
        let p = if self.deformed {
            self.surface.previous_position(v)
        } else {
            self.surface.mesh().positions()[v as usize]
        };
        placed(&self.start_pose, p)
    }

    fn end(&self, v: u32) -> DVec3 {
        placed(&self.end_pose, self.surface.mesh().positions()[v as usize])
    }

    fn trajectory(&self, v: u32) -> Trajectory {
        Trajectory::new(self.start(v), self.end(v))
    }

    fn corners(&self, t: u32) -> [u32; 3] {
        self.surface.mesh().triangles()[t as usize]
    }

    /// How far vertex `v` moves over the step (in the first mesh's frame).
    fn reach(&self, v: u32) -> f64 {
        (self.end(v) - self.start(v)).length()
    }

    /// The box around triangle `t` at each time of the step (its corners move linearly).
    fn moving_box(&self, t: u32) -> MovingBox {
        MovingBox::around(&self.corners(t).map(|v| self.trajectory(v)))
    }

    /// The box swept by triangle `t`, grown by `margin`.
    fn swept_box(&self, t: u32, margin: f64) -> [DVec3; 2] {
        let mut lo = DVec3::splat(f64::INFINITY);
        let mut hi = DVec3::splat(f64::NEG_INFINITY);
        for v in self.corners(t) {
            let (s, e) = (self.start(v), self.end(v));
            lo = lo.min(s.min(e));
            hi = hi.max(s.max(e));
        }
        [lo - DVec3::splat(margin), hi + DVec3::splat(margin)]
    }
}

fn boxes_meet(a: &[DVec3; 2], b: &[DVec3; 2]) -> bool {
    a[0].cmple(b[1]).all() && b[0].cmple(a[1]).all()
}

/// Which features of a triangle pair touched first.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Touching {
    /// A corner of the second triangle on the first's face.
    VertexOfB(u32),
    /// A corner of the first triangle on the second's face.
    VertexOfA(u32),
    /// An edge of each (their end vertices).
    EdgeEdge([u32; 2], [u32; 2]),
}

/// A triangle pair that touched during the step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Crossing {
    pub ta: u32,
    pub tb: u32,
    /// The earliest time in `[0, 1)` of the step at which they touch.
    pub time: f64,
    touching: Touching,
}

/// What the continuous check of one step did.
#[derive(Debug, Default, Clone, Copy, PartialEq, Eq)]
pub(crate) struct SweepCounts {
    /// Kept pairs whose neighbourhoods were swept.
    pub swept: usize,
    /// Kept pairs not swept because the step's deadline had passed.
    pub skipped: usize,
    /// Triangle pairs decided by the continuous primitives (their swept boxes met).
    pub triangle_pairs: usize,
}

/// Reused buffers of the continuous check (nothing is allocated once they have grown).
#[derive(Debug, Default, Clone)]
pub(crate) struct SweepScratch {
    epoch: u32,
    vertex_marks: [Vec<u32>; 2],
    triangle_marks: [Vec<u32>; 2],
    frontier: Vec<u32>,
    next: Vec<u32>,
    neighbourhood: Vec<u32>,
    triangles_a: Vec<u32>,
    triangles_b: Vec<(u32, [DVec3; 2])>,
    tested: HashSet<(u32, u32)>,
    ccd: CcdScratch,
    /// The crossings of the last check, earliest first.
    pub crossings: Vec<Crossing>,
}

/// The continuous check of one step.
pub(crate) struct Sweep<'a, E: Fn(u32, u32) -> bool> {
    pub a: SweptSide<'a>,
    pub b: SweptSide<'a>,
    pub self_mode: bool,
    /// Self-collision's excluded triangle pairs (neighbours along the surface).
    pub excluded: E,
    /// The surfaces' size (for the distance tolerance).
    pub size: f64,
}

impl<E: Fn(u32, u32) -> bool> Sweep<'_, E> {
    /// Checks the neighbourhoods of `pairs` (triangle of `a`, triangle of `b`), in order, over
    /// the step; `keep_going(k)` says whether the `k`-th pair is still swept (a deadline).
    /// Then follows the crossings found to their neighbouring triangle pairs (as collision
    /// propagation does), adding at most `propagation_limit` crossings that way. The crossings
    /// are in `scratch.crossings`, earliest first, one per triangle pair; pairs already
    /// touching at the start of the step are not crossings.
    pub fn run(
        &self,
        pairs: impl Iterator<Item = (u32, u32)>,
        mut keep_going: impl FnMut(usize) -> bool,
        propagation_limit: usize,
        scratch: &mut SweepScratch,
    ) -> SweepCounts {
        let mut counts = SweepCounts::default();
        scratch.crossings.clear();
        scratch.tested.clear();
        let tol = PrimitiveTolerances {
            distance: SWEEP_DISTANCE * self.size.max(f64::MIN_POSITIVE),
            ..PrimitiveTolerances::default()
        };
        for (k, (ta, tb)) in pairs.enumerate() {
            if !keep_going(k) {
                counts.skipped += 1;
                continue;
            }
            counts.swept += 1;
            self.sweep_pair(ta, tb, &tol, scratch, &mut counts);
        }
        // Where two surfaces crossed, the neighbouring triangles usually crossed too, some of
        // them earlier (the tip of a body that went through, the first part of a fold).
        let mut queue: Vec<(u32, u32)> = scratch.crossings.iter().map(|c| (c.ta, c.tb)).collect();
        let mut added = 0;
        while let Some((ta, tb)) = queue.pop() {
            if added >= propagation_limit {
                break;
            }
            let na = self.a.surface.topology().triangle_neighbours(ta);
            let nb = self.b.surface.topology().triangle_neighbours(tb);
            let next = na
                .iter()
                .map(|&x| (x, tb))
                .chain(nb.iter().map(|&y| (ta, y)));
            for (x, y) in next {
                if added >= propagation_limit {
                    break;
                }
                if let Some(c) = self.test(x, y, &tol, scratch, &mut counts) {
                    scratch.crossings.push(c);
                    queue.push((x, y));
                    added += 1;
                }
            }
        }
        scratch.crossings.sort_by(|x, y| {
            x.time
                .total_cmp(&y.time)
                .then((x.ta, x.tb).cmp(&(y.ta, y.tb)))
        });
        counts
    }

    /// Tests triangles `x` of `a` and `y` of `b` over the step, unless excluded or tested
    /// already in this check.
    fn test(
        &self,
        x: u32,
        y: u32,
        tol: &PrimitiveTolerances,
        s: &mut SweepScratch,
        counts: &mut SweepCounts,
    ) -> Option<Crossing> {
        if self.self_mode && (x == y || (self.excluded)(x, y)) {
            return None;
        }
        let key = if self.self_mode {
            (x.min(y), x.max(y))
        } else {
            (x, y)
        };
        if !s.tested.insert(key) {
            return None;
        }
        // Apart unless the triangles' boxes meet at some time of the step (not only their
        // boxes over the whole step: a fast body sweeps a long box over many triangles it
        // passes only one at a time).
        let (ma, mb) = (self.a.moving_box(x), self.b.moving_box(y));
        overlap_window(&ma, &mb, tol.distance, (0.0, 1.0))?;
        counts.triangle_pairs += 1;
        let (time, touching) = self.triangle_pair_time(x, y, tol, &mut s.ccd)?;
        (time > 0.0).then_some(Crossing {
            ta: x,
            tb: y,
            time,
            touching,
        })
    }

    fn sweep_pair(
        &self,
        ta: u32,
        tb: u32,
        tol: &PrimitiveTolerances,
        s: &mut SweepScratch,
        counts: &mut SweepCounts,
    ) {
        // How far the pair's features moved towards or past each other bounds how far along
        // either surface the place where they meet can be from them.
        let reach = |side: &SweptSide, t: u32| {
            side.corners(t)
                .iter()
                .map(|&v| side.reach(v))
                .fold(0.0, f64::max)
        };
        let moved = reach(&self.a, ta) + reach(&self.b, tb);
        let rings = |side: &SweptSide| {
            let edge = side.surface.mean_edge_length() as f64;
            let extra = if edge > 0.0 {
                (moved / edge).ceil().min(MAX_SWEEP_RINGS as f64) as u32
            } else {
                MAX_SWEEP_RINGS
            };
            (BASE_SWEEP_RINGS + extra).min(MAX_SWEEP_RINGS)
        };
        let (rings_a, rings_b) = (rings(&self.a), rings(&self.b));
        neighbourhood(self.a.surface, ta, rings_a, 0, s);
        let mut triangles_a = std::mem::take(&mut s.triangles_a);
        triangles_a.clone_from(&s.neighbourhood);
        neighbourhood(self.b.surface, tb, rings_b, 1, s);
        let margin = tol.distance;
        // The box swept by the first side's neighbourhood; the second side's triangles outside
        // it cannot touch any of them.
        let mut all_a = [DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)];
        for &x in &triangles_a {
            let bx = self.a.swept_box(x, margin);
            all_a = [all_a[0].min(bx[0]), all_a[1].max(bx[1])];
        }
        s.triangles_b.clear();
        for &y in &s.neighbourhood {
            let by = self.b.swept_box(y, 0.0);
            if boxes_meet(&all_a, &by) {
                s.triangles_b.push((y, by));
            }
        }
        for &x in &triangles_a {
            if s.triangles_b.is_empty() {
                break;
            }
            let bx = self.a.swept_box(x, margin);
            for i in 0..s.triangles_b.len() {
                let (y, by) = s.triangles_b[i];
                if !boxes_meet(&bx, &by) {
                    continue;
                }
                if let Some(c) = self.test(x, y, tol, s, counts) {
                    s.crossings.push(c);
                }
            }
        }
        s.triangles_a = triangles_a;
    }

    /// The earliest time in `[0, 1)` at which triangles `x` of `a` and `y` of `b` touch, and
    /// which features touch then.
    fn triangle_pair_time(
        &self,
        x: u32,
        y: u32,
        tol: &PrimitiveTolerances,
        scratch: &mut CcdScratch,
    ) -> Option<(f64, Touching)> {
        let (ca, cb) = (self.a.corners(x), self.b.corners(y));
        let ja = ca.map(|v| self.a.trajectory(v));
        let jb = cb.map(|v| self.b.trajectory(v));
        let mut best: Option<(f64, Touching)> = None;
        let mut limit = 1.0;
        for i in 0..3 {
            if let Some(t) = vertex_face_time(&jb[i], &ja, tol, limit, scratch) {
                best = Some((t, Touching::VertexOfB(cb[i])));
                limit = t;
            }
            if let Some(t) = vertex_face_time(&ja[i], &jb, tol, limit, scratch) {
                best = Some((t, Touching::VertexOfA(ca[i])));
                limit = t;
            }
        }
        for i in 0..3 {
            let ea = [ja[i], ja[(i + 1) % 3]];
            for j in 0..3 {
                let eb = [jb[j], jb[(j + 1) % 3]];
                if let Some(t) = edge_edge_time(&ea, &eb, tol, limit, scratch) {
                    let edge_a = [ca[i], ca[(i + 1) % 3]];
                    let edge_b = [cb[j], cb[(j + 1) % 3]];
                    best = Some((t, Touching::EdgeEdge(edge_a, edge_b)));
                    limit = t;
                }
            }
        }
        best
    }

    /// The contact of a crossing at the end of the step: the closest points of the two
    /// triangles then, the normal from `a` towards the side `b` came from (the direction
    /// between the triangles at the start of the step), and the depth `b` must move along it
    /// to be back on that side and `thickness` apart.
    pub fn contact(&self, c: &Crossing, thickness: f64) -> Contact {
        let (ca, cb) = (self.a.corners(c.ta), self.b.corners(c.tb));
        let start_a = ca.map(|v| self.a.start(v));
        let start_b = cb.map(|v| self.b.start(v));
        let end_a = ca.map(|v| self.a.end(v));
        let end_b = cb.map(|v| self.b.end(v));
        let before = closest_points_triangle_triangle(&start_a, &start_b);
        let gap = before.point_b - before.point_a;
        let centroid = |t: &[DVec3; 3]| (t[0] + t[1] + t[2]) / 3.0;
        let normal = if gap.length() > SWEEP_DISTANCE * self.size {
            gap.normalize()
        } else {
            // Touching at the start: the first face's normal, turned towards the second.
            let n = (start_a[1] - start_a[0])
                .cross(start_a[2] - start_a[0])
                .normalize_or_zero();
            let n = if n == DVec3::ZERO { DVec3::Y } else { n };
            if n.dot(centroid(&start_b) - centroid(&start_a)) < 0.0 {
                -n
            } else {
                n
            }
        };
        let after = closest_points_triangle_triangle(&end_a, &end_b);
        let behind = end_b
            .iter()
            .map(|&q| -normal.dot(q - after.point_a))
            .fold(f64::NEG_INFINITY, f64::max);
        let depth = if behind > 0.0 {
            thickness + behind
        } else {
            (thickness - after.distance).max(0.0)
        };
        let edge = |side: &SweptSide, [u, v]: [u32; 2], t: u32| {
            side.surface
                .topology()
                .edge_between(u, v)
                .map_or(Feature::Triangle(t), Feature::Edge)
        };
        let (feature_a, feature_b) = match c.touching {
            Touching::VertexOfB(v) => (Feature::Triangle(c.ta), Feature::Vertex(v)),
            Touching::VertexOfA(v) => (Feature::Vertex(v), Feature::Triangle(c.tb)),
            Touching::EdgeEdge(ea, eb) => (edge(&self.a, ea, c.ta), edge(&self.b, eb, c.tb)),
        };
        Contact {
            triangle_a: c.ta,
            triangle_b: c.tb,
            feature_a,
            feature_b,
            point_a: after.point_a.as_vec3(),
            point_b: after.point_b.as_vec3(),
            normal: normal.as_vec3(),
            distance: after.distance as f32,
            depth: depth as f32,
            propagated: false,
            time_of_impact: Some(c.time as f32),
        }
    }
}

/// Writes to `s.neighbourhood` the triangles of `surface` with a corner at most `rings` edge steps
/// from a corner of `t` (marks of `side`, 0 or 1, are used for the walk).
fn neighbourhood(surface: &TrackedSurface, t: u32, rings: u32, side: usize, s: &mut SweepScratch) {
    let topology = surface.topology();
    let (nv, nt) = (topology.vertex_count(), topology.triangle_count());
    if s.epoch == u32::MAX {
        s.epoch = 0;
        for m in s.vertex_marks.iter_mut().chain(s.triangle_marks.iter_mut()) {
            m.fill(0);
        }
    }
    s.epoch += 1;
    let epoch = s.epoch;
    let (vm, tm) = (&mut s.vertex_marks[side], &mut s.triangle_marks[side]);
    if vm.len() != nv {
        vm.clear();
        vm.resize(nv, 0);
    }
    if tm.len() != nt {
        tm.clear();
        tm.resize(nt, 0);
    }
    s.frontier.clear();
    s.next.clear();
    let mut walked: Vec<u32> = std::mem::take(&mut s.neighbourhood);
    walked.clear();
    for v in surface.mesh().triangles()[t as usize] {
        if vm[v as usize] != epoch {
            vm[v as usize] = epoch;
            s.frontier.push(v);
            walked.push(v);
        }
    }
    for _ in 0..rings {
        s.next.clear();
        for &u in &s.frontier {
            for &w in topology.vertex_neighbours(u) {
                if vm[w as usize] != epoch {
                    vm[w as usize] = epoch;
                    s.next.push(w);
                    walked.push(w);
                }
            }
        }
        if s.next.is_empty() {
            break;
        }
        std::mem::swap(&mut s.frontier, &mut s.next);
    }
    // The triangles around the walked vertices (reusing `next` for the list).
    s.next.clear();
    for &v in &walked {
        for &x in topology.vertex_triangles(v) {
            if tm[x as usize] != epoch {
                tm[x as usize] = epoch;
                s.next.push(x);
            }
        }
    }
    walked.clear();
    walked.extend_from_slice(&s.next);
    s.neighbourhood = walked;
}
