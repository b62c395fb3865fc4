//! Mesh collision geometry: random meshes written as ASCII STL, binary STL
//! and OBJ, loaded through a URDF; every vertex (and every point of every
//! triangle) must be inside the capsules, which must not be larger than the
//! bounding sphere.

mod common;

use std::fmt::Write as _;
use std::path::Path;

use capp_urdf::{load, Capsule, CapsuleCount, LoadOptions};
use common::{joint, link, origin, robot, write, LIMIT};
use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3};

/// splitmix64, seeded: the same meshes on every run.
struct Rng(u64);

impl Rng {
    fn unit(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }
    fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.unit()
    }
    fn index(&mut self, n: usize) -> usize {
        ((self.unit() * n as f64) as usize).min(n - 1)
    }
}

struct Mesh {
    vertices: Vec<[f32; 3]>,
    faces: Vec<[usize; 3]>,
}

/// A stretched random cloud; every vertex is on some triangle.
fn random_mesh(rng: &mut Rng) -> Mesh {
    let n = 3 + rng.index(80);
    let stretch = [
        rng.range(0.01, 0.5),
        rng.range(0.01, 0.5),
        rng.range(0.01, 0.5),
    ];
    let vertices = (0..n)
        .map(|_| {
            let mut v = [0.0_f32; 3];
            for (k, c) in v.iter_mut().enumerate() {
                *c = (rng.range(-1.0, 1.0) * stretch[k] + 0.1) as f32;
            }
            v
        })
        .collect();
    let faces = (0..n).map(|k| [k, (k + 1) % n, rng.index(n)]).collect();
    Mesh { vertices, faces }
}

fn ascii_stl(mesh: &Mesh) -> String {
    let mut s = String::from("solid random\n");
    for face in &mesh.faces {
        s.push_str("facet normal 0 0 0\nouter loop\n");
        for &i in face {
            let [x, y, z] = mesh.vertices[i];
            writeln!(s, "vertex {x:?} {y:?} {z:?}").unwrap();
        }
        s.push_str("endloop\nendfacet\n");
    }
    s.push_str("endsolid random\n");
    s
}

fn binary_stl(mesh: &Mesh) -> Vec<u8> {
    let mut bytes = vec![0_u8; 80];
    bytes.extend((mesh.faces.len() as u32).to_le_bytes());
    for face in &mesh.faces {
        bytes.extend([0_u8; 12]);
        for &i in face {
            for c in mesh.vertices[i] {
                bytes.extend(c.to_le_bytes());
            }
        }
        bytes.extend([0_u8; 2]);
    }
    bytes
}

fn obj(mesh: &Mesh) -> String {
    let mut s = String::new();
    for [x, y, z] in &mesh.vertices {
        writeln!(s, "v {x:?} {y:?} {z:?}").unwrap();
    }
    for [a, b, c] in &mesh.faces {
        writeln!(s, "f {} {} {}", a + 1, b + 1, c + 1).unwrap();
    }
    s
}

/// A one-joint robot whose moving link `b` collides as `filename`, placed
/// by `xyz`, `rpy` and `scale`.
fn urdf(filename: &str, xyz: [f64; 3], rpy: [f64; 3], scale: [f64; 3]) -> String {
    let b = format!(
        "<link name=\"b\"><visual><geometry><box size=\"9 9 9\"/></geometry></visual><collision>{}<geometry><mesh filename=\"{filename}\" scale=\"{:?} {:?} {:?}\"/></geometry></collision></link>",
        origin(xyz, rpy),
        scale[0],
        scale[1],
        scale[2]
    );
    robot(&[link("a"), b, joint("j", "revolute", "a", "b", LIMIT)].join("\n"))
}

fn inside(capsules: &[Capsule], p: &Point3<f64>) -> bool {
    capsules.iter().any(|c| c.contains(p, 1e-9))
}

fn check_mesh(
    dir: &Path,
    rng: &mut Rng,
    mesh: &Mesh,
    mesh_file: &str,
    count: CapsuleCount,
    options: &LoadOptions,
) {
    let xyz = [
        rng.range(-0.2, 0.2),
        rng.range(-0.2, 0.2),
        rng.range(-0.2, 0.2),
    ];
    let rpy = [
        rng.range(-3.0, 3.0),
        rng.range(-1.5, 1.5),
        rng.range(-3.0, 3.0),
    ];
    let scale = [
        rng.range(0.2, 2.0),
        rng.range(0.2, 2.0),
        rng.range(-2.0, -0.2),
    ];
    let path = write(dir, "robot.urdf", urdf(mesh_file, xyz, rpy, scale));
    let options = LoadOptions {
        capsules_per_mesh: count,
        ..options.clone()
    };
    let chain = load(&path, &options).unwrap_or_else(|e| panic!("{e}"));
    let capsules = &chain.bodies[1].capsules;
    assert!(!capsules.is_empty());
    assert!(chain.bodies[0].capsules.is_empty(), "visual is never read");
    let place = Isometry3::from_parts(
        Translation3::new(xyz[0], xyz[1], xyz[2]),
        UnitQuaternion::from_euler_angles(rpy[0], rpy[1], rpy[2]),
    );
    let placed: Vec<Point3<f64>> = mesh
        .vertices
        .iter()
        .map(|v| {
            let v = Vector3::new(v[0].into(), v[1].into(), v[2].into());
            place * Point3::from(v.component_mul(&Vector3::from(scale)))
        })
        .collect();
    for p in &placed {
        assert!(
            inside(capsules, p),
            "{mesh_file} {count:?}: vertex {p} outside {capsules:?}"
        );
    }
    for face in &mesh.faces {
        for _ in 0..8 {
            let (mut w0, mut w1) = (rng.unit(), rng.unit());
            if w0 + w1 > 1.0 {
                (w0, w1) = (1.0 - w0, 1.0 - w1);
            }
            let [a, b, c] = face.map(|i| placed[i].coords);
            let p = Point3::from(a + (b - a) * w0 + (c - a) * w1);
            assert!(
                inside(capsules, &p),
                "{mesh_file} {count:?}: surface point {p} outside"
            );
        }
    }
    if count == CapsuleCount::One {
        let centroid = placed.iter().map(|p| p.coords).sum::<Vector3<f64>>() / placed.len() as f64;
        let radius = placed
            .iter()
            .fold(0.0_f64, |m, p| m.max((p.coords - centroid).norm()));
        let sphere = Capsule {
            a: centroid.into(),
            b: centroid.into(),
            radius,
        };
        assert_eq!(capsules.len(), 1);
        assert!(capsules[0].volume() <= sphere.volume() * (1.0 + 1e-9) + 1e-15);
    }
}

#[test]
fn random_meshes_in_three_formats_are_contained() {
    let mut rng = Rng(2024);
    let counts = [
        CapsuleCount::One,
        CapsuleCount::Two,
        CapsuleCount::Three,
        CapsuleCount::Four,
        CapsuleCount::Auto,
    ];
    for round in 0..40 {
        let dir = tempfile::tempdir().unwrap();
        let mesh = random_mesh(&mut rng);
        write(dir.path(), "meshes/ascii.stl", ascii_stl(&mesh));
        write(dir.path(), "meshes/binary.STL", binary_stl(&mesh));
        write(dir.path(), "meshes/cloud.obj", obj(&mesh));
        let count = counts[round % counts.len()];
        for file in ["meshes/ascii.stl", "meshes/binary.STL", "meshes/cloud.obj"] {
            check_mesh(
                dir.path(),
                &mut rng,
                &mesh,
                file,
                count,
                &LoadOptions::default(),
            );
        }
    }
}

#[test]
fn package_and_file_uris_resolve() {
    let mut rng = Rng(5);
    let dir = tempfile::tempdir().unwrap();
    let mesh = random_mesh(&mut rng);
    let shelf = dir.path().join("shelf");
    let packages = dir.path().join("packages");
    std::fs::create_dir_all(&shelf).unwrap();
    let stl = write(&packages, "my_robot/meshes/link.stl", binary_stl(&mesh));
    let options = LoadOptions {
        package_dirs: vec![shelf, packages],
        ..LoadOptions::default()
    };
    let package = "package://my_robot/meshes/link.stl";
    check_mesh(
        dir.path(),
        &mut rng,
        &mesh,
        package,
        CapsuleCount::One,
        &options,
    );
    let file = format!("file://{}", stl.display());
    check_mesh(
        dir.path(),
        &mut rng,
        &mesh,
        &file,
        CapsuleCount::One,
        &LoadOptions::default(),
    );
}

#[test]
fn collada_units_are_applied() {
    // One triangle in centimetres: (0,0,0), (100,0,0), (0,50,0) cm.
    let dae = r##"<?xml version="1.0" encoding="utf-8"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
  <asset><unit meter="0.01" name="centimeter"/><up_axis>Z_UP</up_axis></asset>
  <library_geometries>
    <geometry id="tri" name="tri"><mesh>
      <source id="tri-pos">
        <float_array id="tri-pos-array" count="9">0 0 0 100 0 0 0 50 0</float_array>
        <technique_common><accessor source="#tri-pos-array" count="3" stride="3">
          <param name="X" type="float"/><param name="Y" type="float"/><param name="Z" type="float"/>
        </accessor></technique_common>
      </source>
      <vertices id="tri-vtx"><input semantic="POSITION" source="#tri-pos"/></vertices>
      <triangles count="1"><input semantic="VERTEX" source="#tri-vtx" offset="0"/><p>0 1 2</p></triangles>
    </mesh></geometry>
  </library_geometries>
  <library_visual_scenes>
    <visual_scene id="scene"><node id="n" name="n"><instance_geometry url="#tri"/></node></visual_scene>
  </library_visual_scenes>
  <scene><instance_visual_scene url="#scene"/></scene>
</COLLADA>
"##;
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "tri.dae", dae);
    let path = write(
        dir.path(),
        "robot.urdf",
        urdf("tri.dae", [0.0; 3], [0.0; 3], [1.0; 3]),
    );
    let chain = load(&path, &LoadOptions::default()).unwrap_or_else(|e| panic!("{e}"));
    let capsules = &chain.bodies[1].capsules;
    for p in [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.5, 0.0]] {
        assert!(inside(capsules, &Point3::from(p)), "{p:?}");
    }
    let reach: f64 = capsules
        .iter()
        .map(|c| c.a.coords.norm().max(c.b.coords.norm()) + c.radius)
        .fold(0.0, f64::max);
    assert!(reach < 1.2, "metres, not centimetres: {capsules:?}");
}
