//! Collision meshes, bounded by one primitive each.
//!
//! The checker works with capsules and boxes ([`Shape`]). A URDF link
//! described by a mesh (ROS descriptions of the UR arms give only meshes)
//! is bounded by the smaller of its mesh's oriented bounding box (along the
//! vertices' principal axes) and the capsule round its longest principal
//! axis: every vertex is inside the shape, so a check against it is
//! conservative. Only the vertices are read: binary or ASCII STL, and the
//! `v` lines of Wavefront OBJ (the formats ROS descriptions use for
//! collision); other formats are refused with a reason.

use nalgebra::{Isometry3, Matrix3, Point3, Rotation3, SymmetricEigen, Translation3, Vector3};

use crate::Shape;

/// A triangle mesh: its vertices and its triangles (indices into them).
#[derive(Debug, Clone, PartialEq)]
pub struct Mesh {
    pub points: Vec<Point3<f64>>,
    pub triangles: Vec<[usize; 3]>,
}

/// The mesh of a file's bytes (`name`'s extension gives the format); a
/// reason when it cannot be read.
pub fn read(name: &str, bytes: &[u8]) -> Result<Mesh, String> {
    let lower = name.to_ascii_lowercase();
    let mesh = if lower.ends_with(".obj") {
        obj(bytes)?
    } else if lower.ends_with(".stl") {
        stl(bytes)?
    } else {
        return Err("not an STL or OBJ file (convert it to one of those)".into());
    };
    if mesh.points.is_empty() {
        return Err("the mesh has no vertices".into());
    }
    if mesh
        .points
        .iter()
        .any(|p| !p.coords.iter().all(|v| v.is_finite()))
    {
        return Err("the mesh has a non-finite vertex".into());
    }
    Ok(mesh)
}

/// STL: binary when its length is the 84-byte header and count plus 50
/// bytes per triangle, else ASCII `vertex x y z` lines.
fn stl(bytes: &[u8]) -> Result<Mesh, String> {
    if let Some(count) = bytes.get(80..84) {
        let n = u32::from_le_bytes([count[0], count[1], count[2], count[3]]) as usize;
        if n.checked_mul(50).and_then(|b| b.checked_add(84)) == Some(bytes.len()) {
            let mut points = Vec::with_capacity(3 * n);
            for triangle in bytes[84..].chunks_exact(50) {
                // A normal, then three vertices of three little-endian f32s.
                for v in triangle[12..48].chunks_exact(12) {
                    let f = |i: usize| {
                        f64::from(f32::from_le_bytes([v[i], v[i + 1], v[i + 2], v[i + 3]]))
                    };
                    points.push(Point3::new(f(0), f(4), f(8)));
                }
            }
            return Ok(soup(points));
        }
    }
    let text = std::str::from_utf8(bytes).map_err(|_| {
        "neither a binary STL (its length does not match its triangle count) nor ASCII".to_owned()
    })?;
    Ok(soup(lines_of(text, "vertex")?))
}

/// Every three points a triangle (STL's triangle soup).
fn soup(points: Vec<Point3<f64>>) -> Mesh {
    let triangles = (0..points.len() / 3)
        .map(|t| [3 * t, 3 * t + 1, 3 * t + 2])
        .collect();
    Mesh { points, triangles }
}

/// OBJ: `v x y z` vertices and `f` faces (1-based or negative indices,
/// `i/t/n` forms; polygons as fans).
fn obj(bytes: &[u8]) -> Result<Mesh, String> {
    let text = String::from_utf8_lossy(bytes);
    let points = lines_of(&text, "v")?;
    let mut triangles = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let mut words = line.split_whitespace();
        if words.next() != Some("f") {
            continue;
        }
        let corners = words
            .map(|w| {
                let index: i64 = w.split('/').next()?.parse().ok()?;
                let i = if index < 0 {
                    points.len() as i64 + index
                } else {
                    index - 1
                };
                usize::try_from(i).ok().filter(|&i| i < points.len())
            })
            .collect::<Option<Vec<usize>>>()
            .ok_or_else(|| format!("line {}: a face names no vertex of the file", n + 1))?;
        for k in 1..corners.len().saturating_sub(1) {
            triangles.push([corners[0], corners[k], corners[k + 1]]);
        }
    }
    Ok(Mesh { points, triangles })
}

/// The points of the lines that start with `keyword` and three numbers.
fn lines_of(text: &str, keyword: &str) -> Result<Vec<Point3<f64>>, String> {
    let mut points = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let mut words = line.split_whitespace();
        if words.next() != Some(keyword) {
            continue;
        }
        let mut xyz = [0.0; 3];
        for v in &mut xyz {
            *v = words
                .next()
                .and_then(|w| w.parse::<f64>().ok())
                .ok_or_else(|| format!("line {}: `{keyword}` needs three numbers", n + 1))?;
        }
        points.push(Point3::from(xyz));
    }
    Ok(points)
}

/// What one more piece must save to be worth it (m³, a 7.4 cm cube): each
/// piece is one more shape to check. Measured with the ROS UR10's meshes
/// on development cells (docs/measurements.md, "A robot described as ROS describes
/// it"): 1e-4 cut its links into 23 shapes and a sub-goal's median
/// planning time was 175 µs (the built-in arm's 65); 4e-4 gives 13 shapes
/// and 109 µs, the same packages packed, and its bounds still keep the
/// forearm and wrist 3 as far apart as the meshes are.
const PIECE_COST: f64 = 4e-4;
/// How many slices the long axis is cut at most into (the pieces are runs
/// of them).
const SLICES: usize = 64;

/// Bounds for a mesh, in the frame `place` puts it in: one shape round
/// all its vertices ([`bound`]), or, where a few pieces fit it much more
/// closely (a link with a housing at each end of a tube), one round each
/// piece of the mesh cut across its longest principal axis into runs of
/// slices. Each triangle is clipped to every run it crosses and its
/// clipped corners go to that run's shape, which, being convex, then
/// holds the clipped triangle: the pieces together hold the whole
/// surface, so a check against them is conservative. The runs are the
/// ones whose boxes (in the principal axes) have the least volume,
/// counting [`PIECE_COST`] per piece.
pub fn bounds(mesh: &Mesh, place: &Isometry3<f64>) -> Vec<Shape> {
    let whole = || bound(&mesh.points, place);
    // Without triangles (an OBJ of vertices alone) only the vertices' bound
    // is sure to hold the mesh.
    let Some((mean, axes)) = principal(&mesh.points).filter(|_| !mesh.triangles.is_empty()) else {
        return vec![whole()];
    };
    let along = |p: &Point3<f64>| (axes.inverse() * (p.coords - mean)).x;
    let local: Vec<Vector3<f64>> = mesh
        .points
        .iter()
        .map(|p| axes.inverse() * (p.coords - mean))
        .collect();
    let (lo, hi) = local
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(v.x), b.max(v.x))
        });
    if hi <= lo {
        return vec![whole()];
    }
    // Each slice's extent in the principal axes, from the triangles
    // clipped to it.
    let width = (hi - lo) / SLICES as f64;
    let edge = |k: usize| {
        if k == 0 {
            f64::NEG_INFINITY
        } else if k == SLICES {
            f64::INFINITY
        } else {
            lo + k as f64 * width
        }
    };
    let slice_of = |x: f64| (((x - lo) / width).floor().max(0.0) as usize).min(SLICES - 1);
    let mut slices = vec![None::<(Vector3<f64>, Vector3<f64>)>; SLICES];
    let mut clipped: Vec<Vec<Point3<f64>>> = vec![Vec::new(); SLICES];
    for t in &mesh.triangles {
        let corners = t.map(|i| mesh.points[i]);
        let xs = corners.map(|c| along(&c));
        let first = slice_of(xs.iter().copied().fold(f64::INFINITY, f64::min));
        let last = slice_of(xs.iter().copied().fold(f64::NEG_INFINITY, f64::max));
        for k in first..=last {
            let piece = clip(&corners, &along, edge(k), edge(k + 1));
            for p in &piece {
                let v = axes.inverse() * (p.coords - mean);
                let e = slices[k].get_or_insert((v, v));
                e.0 = e.0.inf(&v);
                e.1 = e.1.sup(&v);
            }
            clipped[k].extend(piece);
        }
    }
    // Least cost of the first j slices, and where its last run starts.
    let box_cost = |run: Option<(Vector3<f64>, Vector3<f64>)>| {
        run.map_or(0.0, |(a, b)| {
            let size = b - a;
            size.x * size.y * size.z + PIECE_COST
        })
    };
    let mut best = vec![(0.0, 0usize); SLICES + 1];
    for j in 1..=SLICES {
        best[j] = (f64::INFINITY, 0);
        let mut run: Option<(Vector3<f64>, Vector3<f64>)> = None;
        for i in (0..j).rev() {
            if let Some((a, b)) = slices[i] {
                run = Some(run.map_or((a, b), |(c, d)| (c.inf(&a), d.sup(&b))));
            }
            let cost = best[i].0 + box_cost(run);
            if cost < best[j].0 {
                best[j] = (cost, i);
            }
        }
    }
    if best[SLICES].1 == 0 {
        return vec![whole()];
    }
    let mut pieces = Vec::new();
    let mut j = SLICES;
    while j > 0 {
        let i = best[j].1;
        if slices[i..j].iter().any(Option::is_some) {
            let points: Vec<Point3<f64>> = clipped[i..j].iter().flatten().copied().collect();
            pieces.push(bound_also(&points, place, Some(&axes)));
        }
        j = i;
    }
    if pieces.is_empty() {
        return vec![whole()];
    }
    pieces.reverse();
    pieces
}

/// The part of triangle `corners` whose `along` lies in `[from, to]`
/// (Sutherland–Hodgman against the two planes); its polygon's corners.
fn clip(
    corners: &[Point3<f64>; 3],
    along: &dyn Fn(&Point3<f64>) -> f64,
    from: f64,
    to: f64,
) -> Vec<Point3<f64>> {
    let mut polygon = corners.to_vec();
    for (plane, keep_above) in [(from, true), (to, false)] {
        if !plane.is_finite() || polygon.is_empty() {
            continue;
        }
        let inside = |p: &Point3<f64>| (along(p) >= plane) == keep_above || along(p) == plane;
        let mut out = Vec::with_capacity(polygon.len() + 1);
        for k in 0..polygon.len() {
            let (a, b) = (polygon[k], polygon[(k + 1) % polygon.len()]);
            let (ia, ib) = (inside(&a), inside(&b));
            if ia {
                out.push(a);
            }
            if ia != ib {
                let (xa, xb) = (along(&a), along(&b));
                let t = ((plane - xa) / (xb - xa)).clamp(0.0, 1.0);
                out.push(a + (b - a) * t);
            }
        }
        polygon = out;
    }
    polygon
}

/// The points' mean and principal axes (longest first, right-handed);
/// `None` for no points.
fn principal(points: &[Point3<f64>]) -> Option<(Vector3<f64>, Rotation3<f64>)> {
    if points.is_empty() {
        return None;
    }
    let n = points.len() as f64;
    let mean = points.iter().map(|p| p.coords).sum::<Vector3<f64>>() / n;
    let covariance = points
        .iter()
        .map(|p| (p.coords - mean) * (p.coords - mean).transpose())
        .sum::<Matrix3<f64>>()
        / n;
    let eigen = SymmetricEigen::new(covariance);
    let mut order = [0, 1, 2];
    order.sort_by(|&a, &b| eigen.eigenvalues[b].total_cmp(&eigen.eigenvalues[a]));
    let long = eigen.eigenvectors.column(order[0]).normalize();
    let mid = eigen.eigenvectors.column(order[1]).normalize();
    Some((
        mean,
        Rotation3::from_basis_unchecked(&[long, mid, long.cross(&mid)]),
    ))
}

/// The least-volume shape that holds every point of `points` (at least
/// one), placed by `place`: the oriented bounding box, the capsule round
/// the principal axis, or a cylinder along one of the principal axes.
pub fn bound(points: &[Point3<f64>], place: &Isometry3<f64>) -> Shape {
    bound_also(points, place, None)
}

/// The points' box in `axes` (about `mean`): its centre and half extents.
fn box_in(
    points: &[Point3<f64>],
    mean: &Vector3<f64>,
    axes: &Rotation3<f64>,
) -> (Vector3<f64>, Vector3<f64>) {
    let (mut lo, mut hi) = (
        Vector3::repeat(f64::INFINITY),
        Vector3::repeat(f64::NEG_INFINITY),
    );
    for p in points {
        let v = axes.inverse() * (p.coords - mean);
        lo = lo.inf(&v);
        hi = hi.sup(&v);
    }
    (mean + axes * ((hi + lo) / 2.0), (hi - lo) / 2.0)
}

/// [`bound`], with the box in `also` tried beside the points' own
/// principal axes (a piece of a mesh whose cross-section is square has
/// no principal axes across it; the whole mesh's fit it better).
fn bound_also(
    points: &[Point3<f64>],
    place: &Isometry3<f64>,
    also: Option<&Rotation3<f64>>,
) -> Shape {
    let (mean, axes) = principal(points).unwrap_or((Vector3::zeros(), Rotation3::identity()));
    let local: Vec<Vector3<f64>> = points
        .iter()
        .map(|p| axes.inverse() * (p.coords - mean))
        .collect();
    let (mut centre, mut half) = box_in(points, &mean, &axes);
    let mut turn = axes;
    if let Some(other) = also {
        let (c, h) = box_in(points, &mean, other);
        if h.x * h.y * h.z < half.x * half.y * half.z {
            (centre, half, turn) = (c, h, *other);
        }
    }
    let cuboid = Shape::Cuboid {
        pose: place * Isometry3::from_parts(Translation3::from(centre), turn.into()),
        half,
    };
    let box_volume = 8.0 * half.x * half.y * half.z;
    // Cylinders along each axis of the frames tried, through the box's
    // centre: a housing round a joint is one.
    let mut frames = vec![axes];
    frames.extend(also.copied());
    let cylinder = frames
        .iter()
        .flat_map(|f| (0..3).map(move |k| f * Vector3::ith_axis(k).into_inner()))
        .map(|dir| {
            let (mut lo, mut hi, mut radius) = (f64::INFINITY, f64::NEG_INFINITY, 0.0f64);
            for p in points {
                let v = p.coords - centre;
                let t = v.dot(&dir);
                (lo, hi) = (lo.min(t), hi.max(t));
                radius = radius.max((v - dir * t).norm());
            }
            let volume = std::f64::consts::PI * radius * radius * (hi - lo);
            (volume, lo, hi, radius, dir)
        })
        .min_by(|a, b| a.0.total_cmp(&b.0));
    let (lo, hi) = local
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(v.x), b.max(v.x))
        });

    // The capsule round the long axis (through the mean): the radius
    // holds every point's distance from the axis; each end is pulled in
    // as far as every point stays within the radius of the segment.
    let radial = |v: &Vector3<f64>| v.y.hypot(v.z);
    let radius = local.iter().map(radial).fold(0.0, f64::max);
    let reach = |v: &Vector3<f64>| (radius * radius - radial(v).powi(2)).max(0.0).sqrt();
    let a = local
        .iter()
        .map(|v| v.x + reach(v))
        .fold(f64::INFINITY, f64::min);
    let b = local
        .iter()
        .map(|v| v.x - reach(v))
        .fold(f64::NEG_INFINITY, f64::max);
    let (a, b) = if a <= b { (a, b) } else { (lo, hi) };
    let capsule_volume = std::f64::consts::PI * radius * radius * ((b - a) + 4.0 / 3.0 * radius);
    let mut best = (box_volume, cuboid);
    if radius > 0.0 && capsule_volume < best.0 {
        let end = |x: f64| place * Point3::from(mean + axes * Vector3::new(x, 0.0, 0.0));
        best = (
            capsule_volume,
            Shape::Capsule {
                a: end(a),
                b: end(b),
                radius,
            },
        );
    }
    if let Some((volume, lo, hi, radius, dir)) = cylinder
        && radius > 0.0
        && hi > lo
        && volume < best.0
    {
        let end = |t: f64| place * Point3::from(centre + dir * t);
        best = (
            volume,
            Shape::Cylinder {
                a: end(lo),
                b: end(hi),
                radius,
            },
        );
    }
    best.1
}

#[cfg(test)]
mod tests {
    use super::*;

    fn vertices(name: &str, bytes: &[u8]) -> Result<Vec<Point3<f64>>, String> {
        read(name, bytes).map(|m| m.points)
    }

    /// Whether `p` is inside `shape` (to 1e-9).
    fn inside(shape: &Shape, p: &Point3<f64>) -> bool {
        match shape {
            Shape::Capsule { a, b, radius } => {
                let ab = b - a;
                let t = if ab.norm_squared() > 0.0 {
                    ((p - a).dot(&ab) / ab.norm_squared()).clamp(0.0, 1.0)
                } else {
                    0.0
                };
                (p - (a + ab * t)).norm() <= radius + 1e-9
            }
            Shape::Cuboid { pose, half } => {
                let l = pose.inverse() * p;
                (0..3).all(|i| l[i].abs() <= half[i] + 1e-9)
            }
            Shape::Cylinder { a, b, radius } => {
                let ab = b - a;
                let t = (p - a).dot(&ab) / ab.norm_squared();
                (-1e-9..=1.0 + 1e-9).contains(&t) && (p - (a + ab * t)).norm() <= radius + 1e-9
            }
        }
    }

    /// A closed box mesh from `lo` to `hi` (12 triangles).
    fn cuboid(lo: [f64; 3], hi: [f64; 3], mesh: &mut Mesh) {
        let base = mesh.points.len();
        for i in 0..8 {
            let pick = |k: usize| if i >> k & 1 == 1 { hi[k] } else { lo[k] };
            mesh.points.push(Point3::new(pick(0), pick(1), pick(2)));
        }
        let quads = [
            [0, 1, 3, 2],
            [4, 5, 7, 6],
            [0, 1, 5, 4],
            [2, 3, 7, 6],
            [0, 2, 6, 4],
            [1, 3, 7, 5],
        ];
        for q in quads {
            mesh.triangles.push([base + q[0], base + q[1], base + q[2]]);
            mesh.triangles.push([base + q[0], base + q[2], base + q[3]]);
        }
    }

    /// Points over every triangle of `mesh` (corners, edge midpoints,
    /// centroid).
    fn surface(mesh: &Mesh) -> Vec<Point3<f64>> {
        mesh.triangles
            .iter()
            .flat_map(|t| {
                let [a, b, c] = t.map(|i| mesh.points[i]);
                [
                    a,
                    b,
                    c,
                    a + (b - a) / 2.0,
                    b + (c - b) / 2.0,
                    a + (c - a) / 2.0,
                    a + ((b - a) + (c - a)) / 3.0,
                ]
            })
            .collect()
    }

    #[test]
    fn a_mesh_of_vertices_alone_is_bounded_round_them() {
        let mesh = read("cloud.obj", b"v 0 0 0\nv 0.3 0 0\nv 0 0.1 0\nv 0 0 0.05\n").unwrap();
        let shapes = bounds(&mesh, &Isometry3::identity());
        assert_eq!(shapes.len(), 1);
        assert!(mesh.points.iter().all(|p| inside(&shapes[0], p)));
    }

    #[test]
    fn a_link_with_a_housing_at_each_end_is_cut_into_pieces_that_hold_it() {
        // Two housings 12 cm across joined by a 6 cm tube 60 cm long, as a
        // UR forearm: one shape would fill the room beside the tube.
        let mut mesh = Mesh {
            points: Vec::new(),
            triangles: Vec::new(),
        };
        cuboid([-0.06, -0.06, -0.06], [0.06, 0.06, 0.06], &mut mesh);
        cuboid([0.06, -0.03, -0.03], [0.66, 0.03, 0.03], &mut mesh);
        cuboid([0.66, -0.06, -0.06], [0.78, 0.06, 0.06], &mut mesh);
        let place = Isometry3::new(Vector3::new(0.1, 0.2, 0.3), Vector3::new(0.3, -0.2, 0.5));
        let pieces = bounds(&mesh, &place);
        assert!((2..=5).contains(&pieces.len()), "{pieces:?}");
        for p in surface(&mesh) {
            let p = place * p;
            assert!(pieces.iter().any(|s| inside(s, &p)), "{p} is in no piece");
        }
        // Beside the tube, which one shape would hold, is outside them all.
        let beside = place * Point3::new(0.36, 0.055, 0.0);
        assert!(!pieces.iter().any(|s| inside(s, &beside)));
    }

    proptest::proptest! {
        #[test]
        fn every_point_of_a_random_mesh_is_inside_its_bounds(
            boxes in proptest::collection::vec(
                (proptest::array::uniform3(-0.3f64..0.3), proptest::array::uniform3(0.005f64..0.2)),
                1..5,
            ),
            turn in proptest::array::uniform3(-3.0f64..3.0),
        ) {
            let mut mesh = Mesh { points: Vec::new(), triangles: Vec::new() };
            for (centre, size) in &boxes {
                let lo = std::array::from_fn(|k| centre[k] - size[k] / 2.0);
                let hi = std::array::from_fn(|k| centre[k] + size[k] / 2.0);
                cuboid(lo, hi, &mut mesh);
            }
            let place = Isometry3::new(Vector3::new(0.5, -0.2, 0.1), Vector3::from(turn));
            let pieces = bounds(&mesh, &place);
            proptest::prop_assert!(!pieces.is_empty());
            for p in surface(&mesh) {
                let p = place * p;
                proptest::prop_assert!(pieces.iter().any(|s| inside(s, &p)), "{} is in no piece of {:?}", p, pieces);
            }
        }
    }

    fn binary_stl(triangles: &[[[f32; 3]; 3]]) -> Vec<u8> {
        let mut out = vec![0u8; 80];
        out.extend((triangles.len() as u32).to_le_bytes());
        for t in triangles {
            out.extend([0u8; 12]);
            for v in t {
                for x in v {
                    out.extend(x.to_le_bytes());
                }
            }
            out.extend([0u8; 2]);
        }
        out
    }

    #[test]
    fn binary_and_ascii_stl_and_obj_give_their_vertices() {
        let t = [[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 2.0, 0.5]]];
        let binary = vertices("link.STL", &binary_stl(&t)).unwrap();
        assert_eq!(binary.len(), 3);
        assert_eq!(binary[2], Point3::new(0.0, 2.0, 0.5));
        let ascii = "solid x\n facet normal 0 0 1\n  outer loop\n   vertex 0 0 0\n   vertex 1 0 0\n   vertex 0 2 0.5\n  endloop\n endfacet\nendsolid x\n";
        assert_eq!(vertices("link.stl", ascii.as_bytes()).unwrap(), binary);
        let obj = "# a triangle\nv 0 0 0\nv 1 0 0\nv 0 2 0.5\nvn 0 0 1\nf 1 2 3\n";
        assert_eq!(vertices("link.obj", obj.as_bytes()).unwrap(), binary);
    }

    #[test]
    fn unreadable_meshes_are_refused_with_reasons() {
        assert!(
            vertices("arm.dae", b"<COLLADA/>")
                .unwrap_err()
                .contains("STL or OBJ")
        );
        assert!(
            vertices("arm.obj", b"# nothing\n")
                .unwrap_err()
                .contains("no vertices")
        );
        assert!(
            vertices("arm.obj", b"v 1 2\n")
                .unwrap_err()
                .contains("line 1")
        );
        assert!(vertices("arm.stl", &[0xff; 90]).is_err());
        assert!(
            vertices("arm.obj", b"v 1 2 NaN\n")
                .unwrap_err()
                .contains("non-finite")
        );
    }

    #[test]
    fn a_tube_is_bounded_by_a_cylinder_and_a_flat_mesh_by_a_box() {
        // A cylinder-like cloud along a tilted axis: a cylinder.
        let axis = Vector3::new(1.0, 1.0, 0.3).normalize();
        let across = axis.cross(&Vector3::z()).normalize();
        let up = axis.cross(&across);
        let mut tube = Vec::new();
        for i in 0..=20 {
            for k in 0..12 {
                let a = f64::from(k) * std::f64::consts::TAU / 12.0;
                let c = axis * (f64::from(i) * 0.03) + (across * a.cos() + up * a.sin()) * 0.05;
                tube.push(Point3::from(c + Vector3::new(0.2, -0.1, 0.4)));
            }
        }
        let place = Isometry3::translation(0.0, 0.0, 1.0);
        let shape = bound(&tube, &place);
        assert!(matches!(shape, Shape::Cylinder { .. }), "{shape:?}");
        assert!(tube.iter().all(|p| inside(&shape, &(place * p))));
        if let Shape::Cylinder { a, b, radius } = shape {
            assert!((0.05..0.051).contains(&radius), "{radius}");
            assert!(((b - a).norm() - 0.6).abs() < 1e-3, "{a} {b}");
        }
        // A capsule's surface (a tube with round ends): a capsule.
        let mut pill = Vec::new();
        for i in 0..=12 {
            for k in 0..12 {
                let (lat, lon) = (
                    f64::from(i) * std::f64::consts::PI / 12.0,
                    f64::from(k) * std::f64::consts::TAU / 12.0,
                );
                let v =
                    Vector3::new(lat.cos(), lat.sin() * lon.cos(), lat.sin() * lon.sin()) * 0.05;
                let shift = if v.x >= 0.0 { 0.15 } else { -0.15 };
                pill.push(Point3::from(v + Vector3::new(shift, 0.0, 0.0)));
            }
        }
        let shape = bound(&pill, &Isometry3::identity());
        assert!(matches!(shape, Shape::Capsule { .. }), "{shape:?}");
        assert!(pill.iter().all(|p| inside(&shape, p)));

        // A thin plate: a box.
        let plate: Vec<Point3<f64>> = (0..8)
            .map(|i| {
                let b = |k: u32| if i >> k & 1 == 1 { 1.0 } else { -1.0 };
                Point3::new(0.2 * b(0), 0.1 * b(1), 0.005 * b(2))
            })
            .collect();
        let shape = bound(&plate, &Isometry3::identity());
        assert!(matches!(shape, Shape::Cuboid { .. }), "{shape:?}");
        assert!(plate.iter().all(|p| inside(&shape, p)));
        if let Shape::Cuboid { half, .. } = shape {
            let mut h: Vec<f64> = half.iter().copied().collect();
            h.sort_by(f64::total_cmp);
            assert!(
                (h[0] - 0.005).abs() < 1e-9 && (h[2] - 0.2).abs() < 1e-9,
                "{h:?}"
            );
        }
    }
}
