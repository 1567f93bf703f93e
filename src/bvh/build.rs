//! Binned surface-area-heuristic build, parallel over subtrees for large meshes.
use glam::{Vec3, Vec3A};

use super::tree::{Bvh, BvhNode};
use crate::mesh::TriMesh;

/// Parameters of [`Bvh::build_with`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BvhBuildOptions {
    /// Largest number of triangles in a leaf (clamped to 1..=255; 4 by default). Smaller
    /// leaves cull more triangle pairs but visit more nodes.
    pub max_leaf_size: u32,
    /// Number of SAH bins per axis (clamped to 2..=32).
    pub bins: usize,
    /// Search split planes on all three axes (`true`) or only along the longest extent of the
    /// centroids (`false`, the default: one axis binned per node instead of three).
    pub all_axes: bool,
    /// Build subtrees of at least this many triangles on separate threads (`usize::MAX`: never;
    /// values below 1024 count as 1024: smaller subtrees are built on the thread that splits
    /// them). Threads are only used when the machine has more than one core.
    pub parallel_threshold: usize,
}

impl Default for BvhBuildOptions {
    fn default() -> Self {
        Self {
            max_leaf_size: 4,
            bins: 16,
            all_axes: false,
            parallel_threshold: 2048,
        }
    }
}

/// Cost of visiting a node relative to testing one triangle, in the SAH.
const TRAVERSAL_COST: f32 = 1.0;
const MAX_BINS: usize = 32;

/// Box in SIMD-friendly form, for the build only.
#[derive(Clone, Copy)]
struct Bounds {
    min: Vec3A,
    max: Vec3A,
}

impl Bounds {
    const EMPTY: Bounds = Bounds {
        min: Vec3A::splat(f32::INFINITY),
        max: Vec3A::splat(f32::NEG_INFINITY),
    };
    #[inline]
    fn union(&self, o: &Bounds) -> Bounds {
        Bounds {
            min: self.min.min(o.min),
            max: self.max.max(o.max),
        }
    }
    #[inline]
    fn grow(&mut self, p: Vec3A) {
        self.min = self.min.min(p);
        self.max = self.max.max(p);
    }
    #[inline]
    fn area(&self) -> f32 {
        let e = (self.max - self.min).max(Vec3A::ZERO);
        2.0 * (e.x * e.y + e.y * e.z + e.z * e.x)
    }
}

/// One triangle's box and index, 32 bytes. The build partitions these in place, so every pass
/// reads memory in order (no indirection through an index array).
#[derive(Clone, Copy)]
#[repr(C)]
struct Prim {
    min: Vec3,
    id: u32,
    max: Vec3,
    _pad: u32,
}

impl Prim {
    #[inline]
    fn bounds(&self) -> Bounds {
        Bounds {
            min: self.min.into(),
            max: self.max.into(),
        }
    }
    #[inline]
    fn centroid(&self) -> Vec3A {
        (Vec3A::from(self.min) + Vec3A::from(self.max)) * 0.5
    }
}

/// Build parameters after clamping.
#[derive(Clone, Copy)]
struct Params {
    max_leaf: usize,
    bins: usize,
    all_axes: bool,
    parallel_threshold: usize,
}

/// A subtree under construction: local node indices (root at 0), leaf `first` relative to the
/// start of its triangle range.
struct Subtree {
    nodes: Vec<BvhNode>,
    depth: u32,
}

impl Bvh {
    /// Builds the tree with the default [`BvhBuildOptions`].
    pub fn build(mesh: &TriMesh) -> Bvh {
        Self::build_with(mesh, BvhBuildOptions::default())
    }

    /// Builds the tree: binned SAH over triangle centroids, leaves of at most
    /// `options.max_leaf_size` triangles; large subtrees are built in parallel. Degenerate
    /// triangles and coincident centroids are fine (they are split by count when no plane
    /// separates them). The result does not depend on the number of threads.
    pub fn build_with(mesh: &TriMesh, options: BvhBuildOptions) -> Bvh {
        let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
        let params = Params {
            max_leaf: options.max_leaf_size.clamp(1, 255) as usize,
            bins: options.bins.clamp(2, MAX_BINS),
            all_axes: options.all_axes,
            parallel_threshold: if cores > 1 {
                options.parallel_threshold.max(1024)
            } else {
                usize::MAX
            },
        };
        let pos = mesh.positions();
        let mut bounds = Bounds::EMPTY;
        let mut cbounds = Bounds::EMPTY;
        let mut prims: Vec<Prim> = mesh
            .triangles()
            .iter()
            .enumerate()
            .map(|(id, &[a, b, c])| {
                let (a, b, c) = (pos[a as usize], pos[b as usize], pos[c as usize]);
                let prim = Prim {
                    min: a.min(b).min(c),
                    id: id as u32,
                    max: a.max(b).max(c),
                    _pad: 0,
                };
                bounds = bounds.union(&prim.bounds());
                cbounds.grow(prim.centroid());
                prim
            })
            .collect();
        let tree = build_subtree(&mut prims, bounds, cbounds, params);
        let order = prims.iter().map(|p| p.id).collect();
        Bvh {
            nodes: tree.nodes,
            leaf_triangles: order,
            depth: tree.depth,
        }
    }
}

/// Builds the subtree over `prims` (whose bounds and centroid bounds are given): splits the top
/// node and recurses on two threads when large, else builds serially.
fn build_subtree(prims: &mut [Prim], bounds: Bounds, cbounds: Bounds, params: Params) -> Subtree {
    if prims.len() < params.parallel_threshold {
        return build_serial(prims, bounds, cbounds, params);
    }
    let mut scratch = [(Bounds::EMPTY, 0); 3 * MAX_BINS];
    let Some(split) = split_node(prims, &bounds, &cbounds, params, &mut scratch) else {
        return build_serial(prims, bounds, cbounds, params);
    };
    let (left_prims, right_prims) = prims.split_at_mut(split.mid);
    let (left, right) = std::thread::scope(|s| {
        let handle = s.spawn(|| build_subtree(left_prims, split.left.0, split.left.1, params));
        let right = build_subtree(right_prims, split.right.0, split.right.1, params);
        (handle.join().expect("BVH build thread panicked"), right)
    });
    merge(&bounds, left, right, split.mid as u32)
}

/// `[parent, left root, right root, left rest…, right rest…]`, indices remapped so siblings
/// stay adjacent and children follow parents.
fn merge(bounds: &Bounds, left: Subtree, right: Subtree, mid: u32) -> Subtree {
    let (nl, nr) = (left.nodes.len() as u32, right.nodes.len() as u32);
    let map_left = |i: u32| if i == 0 { 1 } else { 2 + i };
    let map_right = |i: u32| if i == 0 { 2 } else { 2 + nl + i - 1 };
    let mut nodes = Vec::with_capacity((1 + nl + nr) as usize);
    nodes.push(BvhNode {
        min: bounds.min.into(),
        first: 1,
        max: bounds.max.into(),
        count: 0,
    });
    let fix = |n: &BvhNode, map: &dyn Fn(u32) -> u32, offset: u32| {
        let mut n = *n;
        n.first = if n.is_leaf() {
            n.first + offset
        } else {
            map(n.first)
        };
        n
    };
    nodes.push(fix(&left.nodes[0], &map_left, 0));
    nodes.push(fix(&right.nodes[0], &map_right, mid));
    nodes.extend(left.nodes[1..].iter().map(|n| fix(n, &map_left, 0)));
    nodes.extend(right.nodes[1..].iter().map(|n| fix(n, &map_right, mid)));
    Subtree {
        nodes,
        depth: 1 + left.depth.max(right.depth),
    }
}

/// The chosen split of a node: where the range is cut and each side's (bounds, centroid bounds).
struct Split {
    mid: usize,
    left: (Bounds, Bounds),
    right: (Bounds, Bounds),
}

/// Iterative depth-first build of a whole subtree on this thread.
fn build_serial(prims: &mut [Prim], bounds: Bounds, cbounds: Bounds, params: Params) -> Subtree {
    let n = prims.len();
    let mut nodes = Vec::with_capacity(2 * n.div_ceil(params.max_leaf).max(1));
    nodes.push(leaf(&bounds, 0, n));
    let mut depth = 1;
    // (node, start, end, level, bounds, centroid bounds)
    let mut stack = vec![(0usize, 0usize, n, 1u32, bounds, cbounds)];
    let mut scratch = [(Bounds::EMPTY, 0); 3 * MAX_BINS];
    while let Some((node, start, end, level, bounds, cbounds)) = stack.pop() {
        depth = depth.max(level);
        let Some(split) = split_node(
            &mut prims[start..end],
            &bounds,
            &cbounds,
            params,
            &mut scratch,
        ) else {
            nodes[node] = leaf(&bounds, start, end - start);
            continue;
        };
        let left = nodes.len();
        nodes.push(leaf(&split.left.0, 0, 0));
        nodes.push(leaf(&split.right.0, 0, 0));
        nodes[node] = BvhNode {
            min: bounds.min.into(),
            first: left as u32,
            max: bounds.max.into(),
            count: 0,
        };
        let mid = start + split.mid;
        stack.push((left + 1, mid, end, level + 1, split.right.0, split.right.1));
        stack.push((left, start, mid, level + 1, split.left.0, split.left.1));
    }
    Subtree { nodes, depth }
}

fn leaf(b: &Bounds, first: usize, count: usize) -> BvhNode {
    BvhNode {
        min: b.min.into(),
        first: first as u32,
        max: b.max.into(),
        count: count as u32,
    }
}

/// Decides whether to split `range` and partitions it if so (binned SAH along the longest
/// centroid axis, or all three in one pass; by count when no plane separates the centroids).
/// `None`: make a leaf. `scratch` holds the bins.
fn split_node(
    range: &mut [Prim],
    bounds: &Bounds,
    cbounds: &Bounds,
    params: Params,
    scratch: &mut [(Bounds, u32); 3 * MAX_BINS],
) -> Option<Split> {
    let count = range.len();
    if count <= 1 {
        return None;
    }
    // Fewer bins for small nodes: most of a 16-bin sweep over 3 triangles is empty planes.
    let nb = params.bins.min(count.max(4));
    let extent = cbounds.max - cbounds.min;
    let scale = Vec3A::select(
        extent.cmpgt(Vec3A::ZERO),
        Vec3A::splat(nb as f32) / extent,
        Vec3A::ZERO,
    );
    let last_bin = (nb - 1) as f32;
    // Scale vectors that keep one axis: the bin index is one multiply and a horizontal sum.
    let axis_scale = [scale * Vec3A::X, scale * Vec3A::Y, scale * Vec3A::Z];
    let bin_of = |c: Vec3A, axis: usize| -> usize {
        ((c - cbounds.min) * axis_scale[axis])
            .element_sum()
            .min(last_bin) as usize
    };
    let axes = if params.all_axes {
        0..3
    } else {
        let longest = extent.max_position();
        longest..longest + 1
    };
    // Only the bins in use are reset: this runs once per node.
    let bins = &mut scratch[..3 * nb];
    for axis in axes.clone() {
        let bins = &mut bins[axis * nb..(axis + 1) * nb];
        bins.fill((Bounds::EMPTY, 0));
        for prim in range.iter() {
            let bin = &mut bins[bin_of(prim.centroid(), axis)];
            bin.0 = bin.0.union(&prim.bounds());
            bin.1 += 1;
        }
    }
    let parent_area = bounds.area().max(f32::MIN_POSITIVE);
    let mut best: Option<(usize, usize, f32)> = None; // (axis, last left bin, cost)
    for axis in axes {
        if extent[axis] <= 0.0 || !extent[axis].is_finite() {
            continue;
        }
        let mut right_cost = [0.0f32; MAX_BINS];
        let (mut acc, mut acc_n) = (Bounds::EMPTY, 0u32);
        for i in (1..nb).rev() {
            acc = acc.union(&bins[axis * nb + i].0);
            acc_n += bins[axis * nb + i].1;
            right_cost[i] = acc.area() * acc_n as f32;
        }
        let (mut acc, mut acc_n) = (Bounds::EMPTY, 0u32);
        for i in 0..nb - 1 {
            acc = acc.union(&bins[axis * nb + i].0);
            acc_n += bins[axis * nb + i].1;
            if acc_n == 0 || acc_n as usize == count {
                continue;
            }
            let cost =
                TRAVERSAL_COST + (acc.area() * acc_n as f32 + right_cost[i + 1]) / parent_area;
            if best.is_none_or(|(_, _, c)| cost < c) {
                best = Some((axis, i, cost));
            }
        }
    }
    match best {
        Some((_, _, cost)) if cost >= count as f32 && count <= params.max_leaf => None,
        Some((axis, last_left, _)) => Some(partition(range, |c| bin_of(c, axis) <= last_left)),
        // No plane separates the centroids (all coincide): split by count.
        None if count > params.max_leaf => {
            let mid = count / 2;
            let side = |r: &[Prim]| {
                let (mut b, mut c) = (Bounds::EMPTY, Bounds::EMPTY);
                for prim in r {
                    b = b.union(&prim.bounds());
                    c.grow(prim.centroid());
                }
                (b, c)
            };
            Some(Split {
                mid,
                left: side(&range[..mid]),
                right: side(&range[mid..]),
            })
        }
        None => None,
    }
}

/// Moves the triangles whose centroid satisfies `left` to the front, collecting both sides'
/// bounds and centroid bounds on the way.
fn partition(range: &mut [Prim], left: impl Fn(Vec3A) -> bool) -> Split {
    let (mut lb, mut lc, mut rb, mut rc) =
        (Bounds::EMPTY, Bounds::EMPTY, Bounds::EMPTY, Bounds::EMPTY);
    let mut i = 0;
    for j in 0..range.len() {
        let prim = range[j];
        let c = prim.centroid();
        if left(c) {
            lb = lb.union(&prim.bounds());
            lc.grow(c);
            range.swap(i, j);
            i += 1;
        } else {
            rb = rb.union(&prim.bounds());
            rc.grow(c);
        }
    }
    Split {
        mid: i,
        left: (lb, lc),
        right: (rb, rc),
    }
}
