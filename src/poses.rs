//! Poses for benchmarks, tests and the `query` example: Klein & Zachmann's near-contact
//! scenario generator, and the `tx,ty,tz,qx,qy,qz,qw` CSV format.
//!
//! The scenario: two meshes at random orientations, the second approaching the first along a
//! random direction; for each, the *first-contact distance* (largest centre offset along the
//! direction at which the surfaces still touch) is found by exact bisection, and the pose is
//! placed at a random offset around it, uniform in `[-spread, spread]` times the diagonal of
//! the first mesh's box ([`near_contact_poses`]): with a small spread the surfaces are close
//! at every pose, where collision queries work hardest.
//!
//! Next: [`crate::deform`], the deformations that benchmark tracking.
use std::io::Write;
use std::path::{Path, PathBuf};

use glam::{Quat, Vec3};
use rand::rngs::Xoshiro256PlusPlus;
use rand::{RngExt, SeedableRng};

use crate::bvh::{CollisionMesh, QueryWorkspace, intersects};
use crate::geometry::Pose;

/// A pose of the second mesh near first contact with the first (at identity).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ApproachPose {
    /// The pose of the second mesh in the first's frame.
    pub pose: Pose,
    /// Unit direction of approach (from the first mesh's box centre towards the second's).
    pub direction: Vec3,
    /// Centre offset along `direction` at first contact.
    pub contact_distance: f32,
    /// Signed offset from first contact along `direction` (negative: deeper than contact).
    pub offset: f32,
    /// The objects' size the offset is relative to (diagonal of the first mesh's box).
    pub size: f32,
}

impl ApproachPose {
    /// The same rotation and direction, at another offset from first contact.
    pub fn at_offset(&self, offset: f32) -> Pose {
        let shift = self.direction * (offset - self.offset);
        Pose {
            rotation: self.pose.rotation,
            translation: self.pose.translation + shift,
        }
    }
}

/// A uniformly distributed random rotation (Shoemake's method).
pub fn random_rotation(rng: &mut impl RngExt) -> Quat {
    let (u1, u2, u3): (f32, f32, f32) = (rng.random(), rng.random(), rng.random());
    let (s1, s2) = ((1.0 - u1).sqrt(), u1.sqrt());
    let (t2, t3) = (std::f32::consts::TAU * u2, std::f32::consts::TAU * u3);
    Quat::from_xyzw(s1 * t2.sin(), s1 * t2.cos(), s2 * t3.sin(), s2 * t3.cos()).normalize()
}

/// A uniformly distributed random unit vector.
pub fn random_direction(rng: &mut impl RngExt) -> Vec3 {
    loop {
        let v = Vec3::new(
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
        );
        let l = v.length_squared();
        if l > 1e-4 && l <= 1.0 {
            return v / l.sqrt();
        }
    }
}

/// The pose that puts `b`'s box centre at `a`'s box centre plus `direction * distance`,
/// rotated by `rotation`.
pub fn approach_pose(
    a: &CollisionMesh,
    b: &CollisionMesh,
    rotation: Quat,
    direction: Vec3,
    distance: f32,
) -> Pose {
    let ca = a.bvh().root_aabb().center();
    let cb = b.bvh().root_aabb().center();
    Pose {
        rotation,
        translation: ca - rotation * cb + direction * distance,
    }
}

/// Largest centre offset along `direction` at which `b` (rotated by `rotation`) touches `a`,
/// to a relative precision of about 1e-6 of the objects' size; `None` if they never touch
/// along this line.
pub fn first_contact_distance(
    a: &CollisionMesh,
    b: &CollisionMesh,
    rotation: Quat,
    direction: Vec3,
    ws: &mut QueryWorkspace,
) -> Option<f32> {
    let ra = a.bvh().root_aabb().half_extents().length();
    let rb = b.bvh().root_aabb().half_extents().length();
    let hit = |d: f32, ws: &mut QueryWorkspace| {
        intersects(
            a,
            &Pose::IDENTITY,
            b,
            &approach_pose(a, b, rotation, direction, d),
            ws,
        )
    };
    // Beyond ra + rb the bounding spheres are apart: no contact. Scan inwards for a touching
    // offset, then bisect the last gap.
    let far = (ra + rb) * 1.001;
    if far <= 0.0 {
        // Two single points (meshes of zero extent): only the offset 0 can touch.
        return hit(0.0, ws).then_some(0.0);
    }
    const STEPS: usize = 64;
    let mut outside = far;
    let mut inside = None;
    for k in 1..=STEPS {
        let d = far * (1.0 - k as f32 / STEPS as f32);
        if hit(d, ws) {
            inside = Some(d);
            break;
        }
        outside = d;
    }
    let mut inside = inside?;
    let tolerance = (ra + rb) * 1e-7;
    while outside - inside > tolerance {
        let mid = 0.5 * (inside + outside);
        if mid <= inside || mid >= outside {
            break;
        }
        if hit(mid, ws) {
            inside = mid;
        } else {
            outside = mid;
        }
    }
    Some(inside)
}

/// `count` poses of `b` near first contact with `a`: random rotation and direction (seeded),
/// offset from first contact uniform in `[-spread, spread] * size`, where `size` is the diagonal
/// of `a`'s box. Directions along which the meshes never touch are skipped and redrawn.
///
/// # Example
/// ```
/// use stochastic_collision::prelude::*;
/// use stochastic_collision::poses::near_contact_poses;
/// let ball = CollisionMesh::new(generate::icosphere(1.0, 2));
/// let poses = near_contact_poses(&ball, &ball, 4, 0.05, 7);
/// assert_eq!(poses.len(), 4);
/// assert!(poses.iter().all(|p| (p.contact_distance - 2.0).abs() < 0.1));
/// ```
pub fn near_contact_poses(
    a: &CollisionMesh,
    b: &CollisionMesh,
    count: usize,
    spread: f32,
    seed: u64,
) -> Vec<ApproachPose> {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
    let mut ws = QueryWorkspace::new();
    let size = a.bvh().root_aabb().extents().length();
    let mut out = Vec::with_capacity(count);
    let mut attempts = 0;
    while out.len() < count && attempts < count * 10 + 10 {
        attempts += 1;
        let rotation = random_rotation(&mut rng);
        let direction = random_direction(&mut rng);
        let offset = if spread > 0.0 {
            rng.random_range(-spread..=spread) * size
        } else {
            0.0
        };
        let Some(contact) = first_contact_distance(a, b, rotation, direction, &mut ws) else {
            continue;
        };
        out.push(ApproachPose {
            pose: approach_pose(a, b, rotation, direction, contact + offset),
            direction,
            contact_distance: contact,
            offset,
            size,
        });
    }
    out
}

/// Why a pose file could not be read.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PoseFileError {
    /// The file could not be read.
    #[error("cannot read {path}: {message}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The operating system's reason.
        message: String,
    },
    /// A line is not a valid pose (or the header is wrong).
    #[error("{path}:{line}: {message}")]
    Malformed {
        /// The file.
        path: PathBuf,
        /// 1-based line number.
        line: usize,
        /// What is wrong.
        message: String,
    },
}

/// The header line of a pose file.
pub const POSE_CSV_HEADER: &str = "tx,ty,tz,qx,qy,qz,qw";

/// Reads a pose file: header `tx,ty,tz,qx,qy,qz,qw`, then one pose per line (blank lines
/// ignored). Quaternions are normalised; a zero, NaN or infinite value is an error naming its line.
pub fn read_poses_csv(path: impl AsRef<Path>) -> Result<Vec<Pose>, PoseFileError> {
    let path = path.as_ref();
    let bytes = std::fs::read(path).map_err(|e| PoseFileError::Io {
        path: path.to_path_buf(),
        message: e.to_string(),
    })?;
    let text = String::from_utf8(bytes).map_err(|e| {
        let line = e.as_bytes()[..e.utf8_error().valid_up_to()]
            .iter()
            .filter(|&&b| b == b'\n')
            .count()
            + 1;
        PoseFileError::Malformed {
            path: path.to_path_buf(),
            line,
            message: "not UTF-8 text".into(),
        }
    })?;
    parse_poses_csv(&text, path)
}

/// Parses pose-file text (see [`read_poses_csv`]); `path` names the source in errors.
pub fn parse_poses_csv(text: &str, path: &Path) -> Result<Vec<Pose>, PoseFileError> {
    let bad = |line: usize, message: String| PoseFileError::Malformed {
        path: path.to_path_buf(),
        line,
        message,
    };
    let mut lines = text.lines().enumerate().map(|(i, l)| (i + 1, l.trim()));
    let header = lines.by_ref().find(|(_, l)| !l.is_empty());
    match header {
        Some((_, h)) if h.split(',').map(str::trim).eq(POSE_CSV_HEADER.split(',')) => {}
        Some((n, h)) => {
            return Err(bad(
                n,
                format!("expected the header `{POSE_CSV_HEADER}`, found `{h}`"),
            ));
        }
        None => {
            return Err(bad(
                1,
                format!("empty file: expected the header `{POSE_CSV_HEADER}`"),
            ));
        }
    }
    let names = ["tx", "ty", "tz", "qx", "qy", "qz", "qw"];
    let mut poses = Vec::new();
    for (n, line) in lines {
        if line.is_empty() {
            continue;
        }
        let fields: Vec<&str> = line.split(',').map(str::trim).collect();
        if fields.len() != 7 {
            return Err(bad(
                n,
                format!(
                    "expected 7 values ({POSE_CSV_HEADER}), found {}",
                    fields.len()
                ),
            ));
        }
        let mut v = [0f32; 7];
        for (k, f) in fields.iter().enumerate() {
            let x: f32 = f
                .parse()
                .map_err(|_| bad(n, format!("{} is not a number: `{f}`", names[k])))?;
            if !x.is_finite() {
                return Err(bad(n, format!("{} is not finite: `{f}`", names[k])));
            }
            v[k] = x;
        }
        let q = Quat::from_xyzw(v[3], v[4], v[5], v[6]);
        let len = q.length();
        if len.is_nan() || len <= 1e-6 || !len.is_finite() {
            return Err(bad(
                n,
                format!(
                    "quaternion ({}, {}, {}, {}) cannot be normalised",
                    v[3], v[4], v[5], v[6]
                ),
            ));
        }
        poses.push(Pose {
            rotation: q / len,
            translation: Vec3::new(v[0], v[1], v[2]),
        });
    }
    Ok(poses)
}

/// Writes poses in the format [`read_poses_csv`] reads (full `f32` precision round-trips).
pub fn write_poses_csv(
    mut out: impl Write,
    poses: impl IntoIterator<Item = Pose>,
) -> std::io::Result<()> {
    writeln!(out, "{POSE_CSV_HEADER}")?;
    for p in poses {
        let (t, q) = (p.translation, p.rotation);
        writeln!(
            out,
            "{},{},{},{},{},{},{}",
            t.x, t.y, t.z, q.x, q.y, q.z, q.w
        )?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn csv_round_trips_and_names_bad_lines() {
        let poses = [
            Pose::new(Vec3::new(1.5, -2.0, 1e-7), Quat::from_rotation_y(0.3)),
            Pose::IDENTITY,
        ];
        let mut buf = Vec::new();
        write_poses_csv(&mut buf, poses.iter().copied()).unwrap();
        let back = parse_poses_csv(std::str::from_utf8(&buf).unwrap(), Path::new("p.csv")).unwrap();
        assert_eq!(back.len(), 2);
        assert!((back[0].translation - poses[0].translation).length() == 0.0);
        assert!(back[0].rotation.abs_diff_eq(poses[0].rotation, 1e-6));

        let err = |text: &str| {
            parse_poses_csv(text, Path::new("p.csv"))
                .unwrap_err()
                .to_string()
        };
        assert_eq!(
            err("tx,ty,tz,qx,qy,qz,qw\n0,0,0,0,0,0,1\n1,2,3\n"),
            "p.csv:3: expected 7 values (tx,ty,tz,qx,qy,qz,qw), found 3"
        );
        assert!(err("tx,ty\n").starts_with("p.csv:1: expected the header"));
        assert!(
            err("tx,ty,tz,qx,qy,qz,qw\n0,0,NaN,0,0,0,1\n").starts_with("p.csv:2: tz is not finite")
        );
        assert!(
            err("tx,ty,tz,qx,qy,qz,qw\n0,0,x,0,0,0,1\n").starts_with("p.csv:2: tz is not a number")
        );
        assert!(err("tx,ty,tz,qx,qy,qz,qw\n0,0,0,0,0,0,0\n").contains("cannot be normalised"));
        assert!(err("").starts_with("p.csv:1: empty file"));
    }
}
