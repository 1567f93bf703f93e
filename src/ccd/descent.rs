//! The search for the earliest contact over the step: both trees descended together, node
//! pairs (over runs of the step's pieces) taken in the order of the earliest time their moving
//! boxes (and, for a mesh that does not turn, their slabs) can meet, so that the search stops
//! as soon as no pair left can meet before the earliest contact found.
use std::cmp::Ordering;
use std::collections::BinaryHeap;

use glam::{DVec3, Vec3};

use super::impact::{ImpactFeatures, TimeOfImpact};
use super::motion::Trajectory;
use super::primitive::{CcdScratch, PrimitiveTolerances, edge_edge_time, vertex_face_time};
use super::swept::{Span, SweptMesh};
use super::window::{MovingBox, MovingSlab, overlap_window, slab_window};
use crate::bvh::TrianglePair;
use crate::geometry::closest_points_segment_segment;

/// Scratch memory of the search (reused between queries).
#[derive(Debug, Default, Clone)]
pub(crate) struct DescentScratch {
    queue: BinaryHeap<NodePair>,
    /// The moving boxes of the nodes in the queue (each worked out once per node pair queued).
    boxes: Vec<MovingBox>,
    leaf_a: Vec<LeafTriangle>,
    leaf_b: Vec<LeafTriangle>,
    features: CcdScratch,
    /// Triangle pairs whose leaves' windows met (counted for the workspace's statistics).
    pub triangle_pairs: u64,
}

/// A pair of nodes and the time window in which their moving boxes meet; ordered so that the
/// queue pops the earliest window first.
#[derive(Debug, Clone, Copy)]
struct NodePair {
    from: f64,
    to: f64,
    a: u32,
    b: u32,
    /// Where the nodes' boxes are in [`DescentScratch::boxes`].
    box_a: u32,
    box_b: u32,
    /// The pieces of the step the boxes cover.
    span: Span,
}

impl PartialEq for NodePair {
    fn eq(&self, other: &Self) -> bool {
        self.cmp(other) == Ordering::Equal
    }
}

impl Eq for NodePair {}

impl PartialOrd for NodePair {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for NodePair {
    fn cmp(&self, other: &Self) -> Ordering {
        // Reversed: the max-heap pops the earliest.
        other
            .from
            .total_cmp(&self.from)
            .then_with(|| (other.a, other.b).cmp(&(self.a, self.b)))
    }
}

/// The earliest contact over the step, or `None`. The node boxes' frame may turn world
/// distances by `growth` in the max norm (see
/// [`BoxFrame::max_norm_growth`](super::swept::BoxFrame::max_norm_growth)); triangles and
/// features are tested in world coordinates, piece by piece.
///
/// Queue entries are node pairs over a run of pieces (at first both roots over the whole
/// step). An entry is split in time (its run halved) while its boxes are loose from the meshes'
/// turning or once both nodes are leaves, and otherwise split in space (the larger node's
/// children); leaf pairs over one piece have their triangle pairs tested.
pub(crate) fn first_impact(
    a: &impl SweptMesh,
    b: &impl SweptMesh,
    tol: &PrimitiveTolerances,
    growth: f64,
    ws: &mut DescentScratch,
) -> Option<TimeOfImpact> {
    search(a, b, tol, growth, &mut SearchLimit::default(), ws).hit
}

/// When a search must stop before it has settled its answer.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct SearchLimit {
    /// Queue pops allowed (`None`: no limit).
    pub pops: Option<u64>,
    /// Instant after which the search stops (read every 16 pops).
    pub deadline: Option<std::time::Instant>,
}

/// What a search found, and whether it finished.
#[derive(Debug, Clone, Copy)]
pub(crate) struct SearchEnd {
    /// The earliest contact found (the earliest there is when `settled`).
    pub hit: Option<TimeOfImpact>,
    /// The search ran to its end: `hit` is the answer. Otherwise the node pairs left in the
    /// queue ([`DescentScratch::frontier`]) may hold an earlier contact.
    pub settled: bool,
    /// Queue pops made.
    pub pops: u64,
    /// Step times at or after this cannot change the answer (the frontier is what lies before).
    pub until: f64,
}

/// A node pair the search left unexplored: its nodes, when its boxes can first meet, and when
/// within its window its boxes' centres come closest and how close (step time).
#[derive(Debug, Clone, Copy)]
pub(crate) struct FrontierPair {
    pub a: u32,
    pub b: u32,
    pub from: f64,
    /// The end of the pair's window (cut at the search's limit).
    pub to: f64,
    pub at: f64,
    pub centre_distance: f64,
    /// How deep the two boxes overlap at `at` ([`overlap_depth`](super::window::overlap_depth)).
    pub depth: f64,
}

impl DescentScratch {
    /// The node pairs left in the queue whose window starts before `until`.
    pub(crate) fn frontier(
        &self,
        pieces: u32,
        until: f64,
    ) -> impl Iterator<Item = FrontierPair> + '_ {
        self.queue
            .iter()
            .filter(move |p| p.from < until)
            .map(move |p| {
                let (ba, bb) = (&self.boxes[p.box_a as usize], &self.boxes[p.box_b as usize]);
                let (k0, k1) = (p.span.0 as f64, p.span.1 as f64);
                let n = pieces as f64;
                let to_span = |t: f64| ((t * n - k0) / (k1 - k0)).clamp(0.0, 1.0);
                let (u0, u1) = (to_span(p.from), to_span(p.to.min(until)));
                // The centres move linearly over the span: their difference d(u) = d0 + u (d1 - d0)
                // is shortest at the clamped foot of the origin on that line.
                let (ca, cb) = (ba.centres(), bb.centres());
                let (d0, d1) = (cb.0 - ca.0, cb.1 - ca.1);
                let dd = d1 - d0;
                let u = if dd.length_squared() > 0.0 {
                    (-d0.dot(dd) / dd.length_squared()).clamp(u0, u1)
                } else {
                    u0
                };
                FrontierPair {
                    a: p.a,
                    b: p.b,
                    from: p.from,
                    to: p.to.min(until),
                    at: (k0 + u * (k1 - k0)) / n,
                    centre_distance: (d0 + u * dd).length(),
                    depth: super::window::overlap_depth(ba.at(u), bb.at(u)),
                }
            })
    }
}

/// [`first_impact`] within `stop`: the earliest contact found, and whether the search settled.
pub(crate) fn search(
    a: &impl SweptMesh,
    b: &impl SweptMesh,
    tol: &PrimitiveTolerances,
    growth: f64,
    stop: &mut SearchLimit,
    ws: &mut DescentScratch,
) -> SearchEnd {
    let pieces = a.pieces().max(b.pieces()).max(1);
    debug_assert!(a.pieces() == b.pieces() || a.pieces().min(b.pieces()) == 1);
    let margin = tol.distance * 1.01;
    let node_margin = margin * growth;
    // Features within the tolerance in each coordinate are within √3 of it along any
    // direction: the margin of the slabs' tests.
    let margins = (node_margin, margin * 3f64.sqrt());
    // The search runs in step time; a piece's tests in piece time.
    let step_tol = PrimitiveTolerances {
        time: tol.time / pieces as f64,
        ..*tol
    };
    let mut best: Option<Found> = None;
    let limit = |best: &Option<Found>| Found::limit(best, &step_tol);
    ws.queue.clear();
    ws.boxes.clear();
    let whole = (0, pieces);
    ws.boxes
        .extend([a.node_box(0, whole), b.node_box(0, whole)]);
    let root = Entry {
        nodes: (0, 0),
        boxes: (0, 1),
        span: whole,
    };
    let slabs = (a.node_slab(0, whole), b.node_slab(0, whole));
    push(
        &mut ws.queue,
        (&ws.boxes, slabs),
        margins,
        pieces,
        root,
        (0.0, 1.0),
    );
    let mut pops = 0u64;
    let mut settled = true;
    while let Some(&next) = ws.queue.peek() {
        let until = limit(&best);
        if next.from >= until {
            // Every pair left starts later: nothing can come before the answer.
            break;
        }
        let out_of_pops = stop.pops.is_some_and(|n| pops >= n);
        let out_of_time = pops.is_multiple_of(16)
            && stop
                .deadline
                .is_some_and(|d| std::time::Instant::now() >= d);
        if out_of_pops || out_of_time {
            settled = false;
            break;
        }
        pops += 1;
        let pair = ws.queue.pop().expect("peeked");
        let (ni, nj) = (
            &a.bvh().nodes()[pair.a as usize],
            &b.bvh().nodes()[pair.b as usize],
        );
        let (box_a, box_b) = (ws.boxes[pair.box_a as usize], ws.boxes[pair.box_b as usize]);
        let within = (pair.from, pair.to.min(until));
        let (leaf_a, leaf_b) = (ni.is_leaf(), nj.is_leaf());
        let span = pair.span;
        if span.1 - span.0 > 1 {
            let slack = a.turn_slack(span).max(b.turn_slack(span));
            let loose = slack > 0.25 * box_a.largest_side().min(box_b.largest_side());
            if (leaf_a && leaf_b) || loose {
                let mid = span.0 + (span.1 - span.0) / 2;
                for half in [(span.0, mid), (mid, span.1)] {
                    ws.boxes.push(a.node_box(pair.a as usize, half));
                    ws.boxes.push(b.node_box(pair.b as usize, half));
                    let n = ws.boxes.len() as u32;
                    let entry = Entry {
                        nodes: (pair.a, pair.b),
                        boxes: (n - 2, n - 1),
                        span: half,
                    };
                    let slabs = (
                        a.node_slab(pair.a as usize, half),
                        b.node_slab(pair.b as usize, half),
                    );
                    let arena = (&ws.boxes[..], slabs);
                    push(&mut ws.queue, arena, margins, pieces, entry, within);
                }
                continue;
            }
        }
        if leaf_a && leaf_b {
            let piece = span.0;
            ws.leaf_a.clear();
            let tris_a = a.bvh().triangles_of(ni).iter();
            ws.leaf_a
                .extend(tris_a.map(|&t| LeafTriangle::new(a, t, piece)));
            ws.leaf_b.clear();
            let tris_b = b.bvh().triangles_of(nj).iter();
            ws.leaf_b
                .extend(tris_b.map(|&t| LeafTriangle::new(b, t, piece)));
            let at = PieceTime { piece, pieces };
            let to_piece = |t: f64| at.to_piece(t).clamp(0.0, 1.0);
            for ta in &ws.leaf_a {
                for tb in &ws.leaf_b {
                    let until = limit(&best);
                    let window = (to_piece(pair.from), to_piece(pair.to.min(until)));
                    let met =
                        overlap_window(&ta.bounds, &tb.bounds, margin, window).and_then(|w| {
                            let (a, b) = (
                                (&ta.bounds, ta.slab.as_ref()),
                                (&tb.bounds, tb.slab.as_ref()),
                            );
                            slab_window(a, b, margins.1, w)
                        });
                    if met.is_none() {
                        continue;
                    }
                    ws.triangle_pairs += 1;
                    let tols = (tol, &step_tol);
                    triangle_pair(ta, tb, tols, at, &mut best, &mut ws.features);
                }
            }
            continue;
        }
        // Split the inner node, or the larger of two; the children's boxes lie in their
        // parent's, so their windows lie in the parent's.
        let split_a = !leaf_a && (leaf_b || box_a.size() >= box_b.size());
        for child in 0..2 {
            let entry = if split_a {
                let i = ni.left() + child;
                ws.boxes.push(a.node_box(i as usize, span));
                Entry {
                    nodes: (i, pair.b),
                    boxes: (ws.boxes.len() as u32 - 1, pair.box_b),
                    span,
                }
            } else {
                let j = nj.left() + child;
                ws.boxes.push(b.node_box(j as usize, span));
                Entry {
                    nodes: (pair.a, j),
                    boxes: (pair.box_a, ws.boxes.len() as u32 - 1),
                    span,
                }
            };
            let (i, j) = (entry.nodes.0 as usize, entry.nodes.1 as usize);
            let slabs = (a.node_slab(i, span), b.node_slab(j, span));
            push(
                &mut ws.queue,
                (&ws.boxes, slabs),
                margins,
                pieces,
                entry,
                within,
            );
        }
    }
    SearchEnd {
        hit: best.map(|f| TimeOfImpact {
            time: f.earliest as f32,
            ..f.candidate.impact(a, b, f.piece, f.piece_time)
        }),
        settled,
        pops,
        until: limit(&best),
    }
}

/// Where a piece lies in the step.
#[derive(Debug, Clone, Copy)]
struct PieceTime {
    piece: u32,
    pieces: u32,
}

impl PieceTime {
    /// Step time of piece time `t`.
    fn to_step(self, t: f64) -> f64 {
        (self.piece as f64 + t) / self.pieces as f64
    }

    /// Piece time of step time `t` (may lie outside `[0, 1]`).
    fn to_piece(self, t: f64) -> f64 {
        t * self.pieces as f64 - self.piece as f64
    }
}

/// A node pair to queue, before its window is known.
#[derive(Debug, Clone, Copy)]
struct Entry {
    nodes: (u32, u32),
    boxes: (u32, u32),
    span: Span,
}

/// The contact kept so far. Where several features meet at once (faces meeting flat, a vertex
/// arriving on an edge shared by two faces), the one whose normal lies most along the relative
/// motion is kept among the roots within `time_tolerance` of the earliest (its normal is the
/// one a response should push along), while the time reported is the earliest root found, so
/// the answer is never late.
#[derive(Debug, Clone, Copy)]
struct Found {
    /// Step time of this root.
    time: f64,
    /// Its piece and the time within it.
    piece: u32,
    piece_time: f64,
    earliest: f64,
    /// `|n · v| / |v|` for the contact normal `n` and the features' relative motion `v`.
    alignment: f64,
    candidate: Candidate,
}

impl Found {
    /// Times at or after this cannot change the answer.
    fn limit(best: &Option<Found>, tol: &PrimitiveTolerances) -> f64 {
        best.as_ref().map_or(1.0 + 1e-12, |f| f.earliest + tol.time)
    }

    /// Keeps the root at `time` of `candidate` if it comes first, or at the same time with a
    /// normal more along the motion.
    fn offer(best: &mut Option<Found>, new: Found, tol: &PrimitiveTolerances) {
        let Some(f) = best else {
            *best = Some(new);
            return;
        };
        let earliest = f.earliest.min(new.time);
        let first = new.time < f.earliest - tol.time;
        let better = new.time <= f.earliest + tol.time && new.alignment > f.alignment;
        if first || better {
            *f = new;
        }
        f.earliest = earliest;
    }
}

/// Queues `entry` if its boxes meet within `within` (step time).
/// `margins`: the boxes' (in the frame's max norm) and the slabs' (Euclidean).
fn push(
    queue: &mut BinaryHeap<NodePair>,
    (arena, slabs): (&[MovingBox], (Option<MovingSlab>, Option<MovingSlab>)),
    (margin, slab_margin): (f64, f64),
    pieces: u32,
    entry: Entry,
    within: (f64, f64),
) {
    let (box_a, box_b) = (
        &arena[entry.boxes.0 as usize],
        &arena[entry.boxes.1 as usize],
    );
    // The boxes move over the span's own time.
    let (k0, k1) = (entry.span.0 as f64, entry.span.1 as f64);
    let n = pieces as f64;
    let to_span = |t: f64| ((t * n - k0) / (k1 - k0)).clamp(0.0, 1.0);
    let to_step = |u: f64| (k0 + u * (k1 - k0)) / n;
    let local = (to_span(within.0), to_span(within.1));
    // The boxes' window, narrowed by the slabs where the nodes have them.
    let window = overlap_window(box_a, box_b, margin, local).and_then(|w| {
        let (a, b) = ((box_a, slabs.0.as_ref()), (box_b, slabs.1.as_ref()));
        slab_window(a, b, slab_margin, w)
    });
    if let Some((from, to)) = window {
        let (from, to) = (to_step(from), to_step(to));
        if from < within.1 {
            queue.push(NodePair {
                from,
                to,
                a: entry.nodes.0,
                b: entry.nodes.1,
                box_a: entry.boxes.0,
                box_b: entry.boxes.1,
                span: entry.span,
            });
        }
    }
}

/// Which features a root was found for (vertex indices of the meshes).
#[derive(Debug, Clone, Copy)]
enum Meeting {
    VertexFace(u32),
    FaceVertex(u32),
    EdgeEdge([u32; 2], [u32; 2]),
}

impl Meeting {
    fn features(self) -> ImpactFeatures {
        match self {
            Meeting::VertexFace(vertex) => ImpactFeatures::VertexFace { vertex },
            Meeting::FaceVertex(vertex) => ImpactFeatures::FaceVertex { vertex },
            Meeting::EdgeEdge(a, b) => ImpactFeatures::EdgeEdge { a, b },
        }
    }
}

/// The features found to meet first, before their contact is worked out.
#[derive(Debug, Clone, Copy)]
struct Candidate {
    triangles: TrianglePair,
    features: Meeting,
}

/// One triangle of a leaf as the tests read it: its index, its vertices and their paths over
/// the piece, and the box around them.
#[derive(Debug, Clone, Copy)]
struct LeafTriangle {
    index: u32,
    corners: [u32; 3],
    paths: [Trajectory; 3],
    bounds: MovingBox,
    /// Along the triangle's normal at the piece's start: its plane then, widened as its
    /// corners move ([`MovingSlab::around`]); `None` for a degenerate triangle.
    slab: Option<MovingSlab>,
}

impl LeafTriangle {
    fn new(mesh: &impl SweptMesh, index: u32, piece: u32) -> Self {
        let corners = mesh.triangles()[index as usize];
        let paths = corners.map(|v| mesh.vertex(v, piece));
        let [p0, p1, p2] = paths.map(|p| p.start);
        let normal = (p1 - p0).cross(p2 - p0).normalize_or_zero();
        Self {
            index,
            corners,
            paths,
            bounds: MovingBox::around(&paths),
            slab: (normal != DVec3::ZERO).then(|| MovingSlab::around(normal, &paths)),
        }
    }
}

/// The contacts of triangles `ta` and `tb` that come before `best`'s: the six vertex–face and
/// nine edge–edge tests, each bounded by the earliest found so far.
fn triangle_pair(
    ta: &LeafTriangle,
    tb: &LeafTriangle,
    (tol, step_tol): (&PrimitiveTolerances, &PrimitiveTolerances),
    at: PieceTime,
    best: &mut Option<Found>,
    scratch: &mut CcdScratch,
) {
    let (fa, fb) = (ta.corners, tb.corners);
    let (va, vb) = (&ta.paths, &tb.paths);
    let edge = |k: usize| [k, (k + 1) % 3];
    let meetings = (0..3)
        .flat_map(|k| [Meeting::VertexFace(k as u32), Meeting::FaceVertex(k as u32)])
        .chain((0..9).map(|k| {
            let (i, j) = (edge(k / 3), edge(k % 3));
            Meeting::EdgeEdge(i.map(|x| x as u32), j.map(|x| x as u32))
        }));
    // Meetings are built with corner numbers (0..3) and reported with vertex indices.
    for m in meetings {
        let limit = at.to_piece(Found::limit(best, step_tol)).min(1.0 + 1e-12);
        // The root, the features, the contact normal at a time and the relative motion.
        let found = match m {
            Meeting::VertexFace(k) => {
                let p = &va[k as usize];
                vertex_face_time(p, vb, tol, limit, scratch).map(|t| {
                    let n = face_normal_towards(vb, p, t);
                    (
                        t,
                        Meeting::VertexFace(fa[k as usize]),
                        n,
                        motion(&[*p]) - motion(vb),
                    )
                })
            }
            Meeting::FaceVertex(k) => {
                let p = &vb[k as usize];
                vertex_face_time(p, va, tol, limit, scratch).map(|t| {
                    let n = face_normal_towards(va, p, t);
                    (
                        t,
                        Meeting::FaceVertex(fb[k as usize]),
                        n,
                        motion(&[*p]) - motion(va),
                    )
                })
            }
            Meeting::EdgeEdge(i, j) => {
                let (ea, eb) = (i.map(|k| va[k as usize]), j.map(|k| vb[k as usize]));
                edge_edge_time(&ea, &eb, tol, limit, scratch).map(|t| {
                    let features =
                        Meeting::EdgeEdge(i.map(|k| fa[k as usize]), j.map(|k| fb[k as usize]));
                    (
                        t,
                        features,
                        edge_contact(&ea, &eb, t).1,
                        motion(&ea) - motion(&eb),
                    )
                })
            }
        };
        if let Some((time, features, normal, relative)) = found {
            let candidate = Candidate {
                triangles: TrianglePair {
                    a: ta.index,
                    b: tb.index,
                },
                features,
            };
            let alignment = normal.dot(relative.normalize_or_zero()).abs();
            let new = Found {
                time: at.to_step(time),
                piece: at.piece,
                piece_time: time,
                earliest: at.to_step(time),
                alignment,
                candidate,
            };
            Found::offer(best, new, step_tol);
        }
    }
}

/// The mean motion of some points over the piece.
fn motion(points: &[Trajectory]) -> DVec3 {
    let sum: DVec3 = points.iter().map(|p| p.end - p.start).sum();
    sum / points.len() as f64
}

impl Candidate {
    /// The contact point and normal at time `t` of piece `piece`.
    fn impact(&self, a: &impl SweptMesh, b: &impl SweptMesh, piece: u32, t: f64) -> TimeOfImpact {
        let (point, normal) = match self.features {
            Meeting::VertexFace(vertex) => {
                let p = a.vertex(vertex, piece);
                let face = b.triangles()[self.triangles.b as usize].map(|v| b.vertex(v, piece));
                // The face's normal, towards the side the vertex comes from.
                let n = face_normal_towards(&face, &p, t);
                (p.at(t), n)
            }
            Meeting::FaceVertex(vertex) => {
                let p = b.vertex(vertex, piece);
                let face = a.triangles()[self.triangles.a as usize].map(|v| a.vertex(v, piece));
                (p.at(t), -face_normal_towards(&face, &p, t))
            }
            Meeting::EdgeEdge(ea, eb) => {
                let (pa, pb) = (
                    ea.map(|v| a.vertex(v, piece)),
                    eb.map(|v| b.vertex(v, piece)),
                );
                edge_contact(&pa, &pb, t)
            }
        };
        TimeOfImpact {
            time: t as f32,
            point: point.as_vec3(),
            normal: normal.as_vec3().normalize_or(Vec3::X),
            triangles: self.triangles,
            features: self.features.features(),
        }
    }
}

/// The unit normal of `face` at time `t`, oriented towards the side `p` comes from (where `p`
/// was at the start, or against `p`'s motion relative to the face when it starts on it).
fn face_normal_towards(face: &[Trajectory; 3], p: &Trajectory, t: f64) -> DVec3 {
    let [x, y, z] = face.map(|v| v.at(t));
    let n = (y - x).cross(z - x).normalize_or_zero();
    let side = n.dot(p.start - face[0].start);
    let relative_motion = (p.end - p.start) - (face[0].end - face[0].start);
    let toward = if side.abs() > 1e-12 {
        side
    } else {
        -n.dot(relative_motion)
    };
    if toward < 0.0 { -n } else { n }
}

/// The contact point (midway between the edges' closest points) and the normal (from `q`
/// towards `p`) of two edges at time `t`.
fn edge_contact(p: &[Trajectory; 2], q: &[Trajectory; 2], t: f64) -> (DVec3, DVec3) {
    let now = closest_points_segment_segment(p[0].at(t), p[1].at(t), q[0].at(t), q[1].at(t));
    let before = closest_points_segment_segment(p[0].start, p[1].start, q[0].start, q[1].start);
    let n = (p[1].at(t) - p[0].at(t))
        .cross(q[1].at(t) - q[0].at(t))
        .normalize_or_zero();
    let apart = before.point_a - before.point_b;
    let relative_motion = (p[0].end - p[0].start) - (q[0].end - q[0].start);
    let n = if n == DVec3::ZERO {
        // Parallel edges: the direction between them, or against their motion.
        if apart.length_squared() > 1e-24 {
            apart.normalize()
        } else {
            -relative_motion.normalize_or(DVec3::X)
        }
    } else if n.dot(apart) < 0.0 || (n.dot(apart) == 0.0 && n.dot(relative_motion) > 0.0) {
        -n
    } else {
        n
    };
    (0.5 * (now.point_a + now.point_b), n)
}
