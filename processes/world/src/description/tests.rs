use super::*;

fn convoy_bot() -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../launch/convoy/robots/convoy_bot.urdf")
}

fn parse_str(text: &str) -> Result<RobotDescription, DescriptionError> {
    parse(text, "arm.urdf", Path::new("."))
}

const LINK: &str = r#"<inertial><mass value="1"/><inertia ixx="0.1" iyy="0.1" izz="0.1" ixy="0" ixz="0" iyz="0"/></inertial>"#;

/// A two-joint arm; `joint2` is spliced in as the second joint's XML.
fn arm(joint2: &str) -> String {
    format!(
        r#"<robot name="arm">
  <link name="base">{LINK}</link>
  <link name="upper">{LINK}</link>
  <link name="lower">{LINK}</link>
  <joint name="shoulder" type="revolute">
    <parent link="base"/><child link="upper"/><axis xyz="0 1 0"/>
    <limit lower="-1" upper="1" effort="10" velocity="2"/>
  </joint>
  {joint2}
</robot>"#
    )
}

const ELBOW: &str = r#"<joint name="elbow" type="revolute">
    <parent link="upper"/><child link="lower"/><origin xyz="0 0 0.5"/><axis xyz="0 2 0"/>
    <limit lower="-2" upper="2" effort="5" velocity="3"/>
  </joint>"#;

#[test]
fn the_convoy_robot_is_a_tree_of_four_links() {
    let d = load_description(&convoy_bot()).unwrap();
    assert_eq!(d.links.len(), 4);
    assert_eq!(d.links[d.root].name, "base_link");
    assert_eq!(d.movable_joints().len(), 2);
    assert!((d.mass() - 1.5).abs() < 1e-12);
    let j = &d.joints[d.joint("left_wheel_joint").unwrap()];
    assert_eq!(j.kind, JointKind::Continuous);
    assert_eq!(j.limits.effort, f64::INFINITY);
    assert_eq!(j.limits.lower, f64::NEG_INFINITY);
}

#[test]
fn an_arm_parses_with_unit_axes_and_rest_poses() {
    let d = parse_str(&arm(ELBOW)).unwrap();
    let elbow = &d.joints[d.joint("elbow").unwrap()];
    assert_eq!(elbow.axis, Vector3::y(), "normalised");
    assert_eq!(elbow.limits.effort, 5.0);
    let poses = d.rest_poses();
    assert!((poses[d.link("lower").unwrap()].translation.vector.z - 0.5).abs() < 1e-12);
    assert_eq!(elbow.line, Some(9));
}

fn error(text: &str) -> String {
    parse_str(text).unwrap_err().to_string()
}

#[test]
fn an_unknown_joint_type_names_the_joint_and_line() {
    let e = error(&arm(&ELBOW.replace("revolute", "hinge")));
    assert!(e.starts_with("arm.urdf:9:"), "{e}");
    assert!(e.contains("joint 'elbow'") && e.contains("'hinge'"), "{e}");
    let e = error(&arm(&ELBOW.replace("revolute", "floating")));
    assert!(
        e.contains("not simulated") && e.contains("floating base"),
        "{e}"
    );
}

#[test]
fn reversed_limits_are_rejected() {
    let e = error(&arm(
        &ELBOW.replace(r#"lower="-2" upper="2""#, r#"lower="2" upper="-2""#)
    ));
    assert!(e.contains("joint 'elbow'") && e.contains("reversed"), "{e}");
    let e = error(&arm(&ELBOW.replace(
        r#"<limit lower="-2" upper="2" effort="5" velocity="3"/>"#,
        "",
    )));
    assert!(e.contains("needs a range"), "{e}");
}

#[test]
fn negative_mass_and_impossible_inertia_name_the_link() {
    let e = error(&arm(ELBOW).replacen(
        r#"<link name="upper"><inertial><mass value="1"/>"#,
        r#"<link name="upper"><inertial><mass value="-1"/>"#,
        1,
    ));
    assert!(
        e.contains("arm.urdf:3:") && e.contains("link 'upper'"),
        "{e}"
    );
    let e = error(&arm(ELBOW).replacen(r#"ixx="0.1""#, r#"ixx="1.0""#, 1));
    assert!(e.contains("link 'base'") && e.contains("inertia"), "{e}");
}

#[test]
fn a_link_without_inertial_is_massless() {
    let d = parse_str(&arm(ELBOW).replacen(
        &format!(r#"<link name="lower">{LINK}</link>"#),
        r#"<link name="lower"/>"#,
        1,
    ))
    .unwrap();
    assert!(d.links[d.link("lower").unwrap()].inertial.is_none());
}

#[test]
fn kinematic_loops_are_rejected() {
    // A second parent for `lower`.
    let second = ELBOW.to_string()
        + r#"<joint name="strut" type="fixed"><parent link="base"/><child link="lower"/></joint>"#;
    let e = error(&arm(&second));
    assert!(
        e.contains("joint 'strut'") && e.contains("kinematic loop"),
        "{e}"
    );
    // base → upper → lower → base: no root at all.
    let cycle = ELBOW.to_string()
        + r#"<joint name="back" type="fixed"><parent link="lower"/><child link="base"/></joint>"#;
    let e = error(&arm(&cycle));
    assert!(e.contains("kinematic loop"), "{e}");
}

#[test]
fn missing_and_disconnected_links_are_rejected() {
    let e = error(&arm(
        &ELBOW.replace(r#"child link="lower""#, r#"child link="forearm""#)
    ));
    assert!(e.contains("child link 'forearm' does not exist"), "{e}");
    let e = error(&arm(""));
    assert!(
        e.contains("[\"lower\"]") && e.contains("not connected"),
        "{e}"
    );
}

/// urdf-rs names a missing attribute but not where: the first element lacking it is named,
/// with its line and its link.
#[test]
fn a_missing_attribute_is_named_with_its_element_link_and_line() {
    let text = "<robot name='x'>\n  <link name='base'>\n    <collision>\n      \
                <geometry><box/></geometry>\n    </collision>\n  </link>\n</robot>\n";
    let e = error(text);
    assert!(e.contains(":4:"), "{e}");
    assert!(e.contains("<box> of link 'base' has no size"), "{e}");
    assert!(e.contains("missing field"), "{e}");
}

#[test]
fn malformed_xml_is_a_clear_error() {
    let e = error("<robot name='x'><link name='a'>");
    assert!(e.contains("not a valid URDF"), "{e}");
}

fn scratch(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("caravan-desc-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn with_mesh(file: &str, scale: &str) -> String {
    arm(ELBOW).replacen(
        r#"<link name="lower">"#,
        &format!(
            r#"<link name="lower"><collision><geometry><mesh filename="{file}" scale="{scale}"/></geometry></collision>"#
        ),
        1,
    )
}

#[test]
fn stl_and_obj_meshes_load_scaled() {
    let dir = scratch("mesh");
    let tri = |a: [f32; 3], b: [f32; 3], c: [f32; 3]| stl_io::Triangle {
        normal: stl_io::Normal::new([0.0, 0.0, 1.0]),
        vertices: [
            stl_io::Vertex::new(a),
            stl_io::Vertex::new(b),
            stl_io::Vertex::new(c),
        ],
    };
    let faces = [
        tri([0., 0., 0.], [1., 0., 0.], [0., 1., 0.]),
        tri([0., 0., 0.], [0., 1., 0.], [0., 0., 1.]),
    ];
    let mut f = std::fs::File::create(dir.join("part.stl")).unwrap();
    stl_io::write_stl(&mut f, faces.iter()).unwrap();
    std::fs::write(
        dir.join("part.obj"),
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\nf 1 3 4\n",
    )
    .unwrap();
    for file in ["part.stl", "part.obj"] {
        let d = parse(&with_mesh(file, "2 2 2"), "arm.urdf", &dir).unwrap();
        let lower = &d.links[d.link("lower").unwrap()];
        let Geometry::Mesh(m) = &lower.collisions[0].geometry else {
            panic!("a mesh")
        };
        assert_eq!(m.triangles.len(), 2, "{file}");
        assert_eq!(m.bounds().1, [2.0, 2.0, 2.0], "{file}");
    }
    let e = parse(&with_mesh("missing.stl", "1 1 1"), "arm.urdf", &dir)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("link 'lower'") && e.contains("missing.stl"),
        "{e}"
    );
    let e = parse(&with_mesh("part.dae", "1 1 1"), "arm.urdf", &dir)
        .unwrap_err()
        .to_string();
    assert!(e.contains("STL and OBJ"), "{e}");
    std::fs::write(
        dir.join("far.obj"),
        "v 0 0 0\nv 1e30 0 0\nv 0 1 0\nv 0 0 nan\nf 1 2 3\nf 1 3 4\n",
    )
    .unwrap();
    let e = parse(&with_mesh("far.obj", "1 1 1"), "arm.urdf", &dir)
        .unwrap_err()
        .to_string();
    assert!(e.contains("far.obj") && e.contains("vertex 1"), "{e}");
}

#[test]
fn gazebo_friction_is_read_and_checked() {
    let with = |mu: &str| {
        arm(ELBOW).replace(
            "</robot>",
            &format!(r#"<gazebo reference="upper"><mu1>{mu}</mu1></gazebo></robot>"#),
        )
    };
    let d = parse_str(&with("0.25")).unwrap();
    assert_eq!(d.links[d.link("upper").unwrap()].friction, Some(0.25));
    let e = error(&with("-1"));
    assert!(e.contains("mu1") && e.contains("upper"), "{e}");
}

#[test]
fn absurd_shape_sizes_name_the_link() {
    for (radius, says) in [("0", "must be positive"), ("1e308", "more than the 100 m")] {
        let text = format!(
            r#"<robot name="r"><link name="wheel">{LINK}<collision><geometry><cylinder radius="{radius}" length="0.02"/></geometry></collision></link></robot>"#
        );
        let e = parse_str(&text).unwrap_err().to_string();
        assert!(
            e.contains("'wheel'") && e.contains("radius") && e.contains(says),
            "{e}"
        );
    }
}

#[test]
fn absurd_origins_and_masses_name_the_joint_or_link() {
    let far = ELBOW.replace(r#"<origin xyz="0 0 0.5"/>"#, r#"<origin xyz="1e5 0 0.5"/>"#);
    let e = parse_str(&arm(&far)).unwrap_err().to_string();
    assert!(
        e.contains("'elbow'") && e.contains("<origin xyz>[0]"),
        "{e}"
    );
    let spun = ELBOW.replace(
        r#"<origin xyz="0 0 0.5"/>"#,
        r#"<origin xyz="0 0 0.5" rpy="0 1e308 0"/>"#,
    );
    let e = parse_str(&arm(&spun)).unwrap_err().to_string();
    assert!(
        e.contains("'elbow'") && e.contains("<origin rpy>[1]"),
        "{e}"
    );
    let heavy = arm(ELBOW).replacen(r#"<mass value="1"/>"#, r#"<mass value="1e308"/>"#, 1);
    let e = parse_str(&heavy).unwrap_err().to_string();
    assert!(e.contains("'base'") && e.contains("0 to 1e6 kg"), "{e}");
}
