use crate::scene::*;
use crate::testutil::load_error;
use crate::with_scene;

const ROTATED: &str = r#"
dim = 4
[camera]
position = [0, 0, 0, 5]
look_at = [0, 0, 0, 0]
up = [[0, 1, 0, 0], [0, 0, 1, 0]]
fov = 40
resolution = 4

[[objects]]
shape = "hypercube"
transform = [{ scale = 0.5 }, { rotate = { quaternions = [[0.6, 0, 0.8, 0], [0.5, 0.5, 0.5, 0.5]] } }]
"#;

fn vertices(text: &str) -> Vec<Vec<f64>> {
    let (_, scene) = load_toml_str(text, "scene.toml", None).unwrap();
    with_scene!(&scene, s, _N => s.objects[0].mesh.vertices.iter().map(|v| v.to_vec()).collect())
}

fn matrix_toml<const N: usize>(m: &crate::linalg::Matrix<N>) -> String {
    let rows: Vec<String> = m
        .iter()
        .map(|r| {
            format!(
                "[{}]",
                r.iter()
                    .map(|x| format!("{x:?}"))
                    .collect::<Vec<_>>()
                    .join(", ")
            )
        })
        .collect();
    format!("{{ matrix = [{}] }}", rows.join(", "))
}

fn assert_same_vertices(a: &[Vec<f64>], b: &[Vec<f64>]) {
    assert_eq!(a.len(), b.len());
    for (x, y) in a.iter().zip(b) {
        for (p, q) in x.iter().zip(y) {
            assert!((p - q).abs() < 1e-15, "{x:?} vs {y:?}");
        }
    }
}

#[test]
fn quaternion_and_rolling_rotations_equal_their_matrices() {
    use crate::rotation::{rolling_ball, so4_from_quaternions, RollingAngle};
    let m = so4_from_quaternions(&[0.6, 0.0, 0.8, 0.0], &[0.5, 0.5, 0.5, 0.5]);
    let by_matrix = ROTATED.replace(
        "{ rotate = { quaternions = [[0.6, 0, 0.8, 0], [0.5, 0.5, 0.5, 0.5]] } }",
        &matrix_toml(&m),
    );
    assert_same_vertices(&vertices(ROTATED), &vertices(&by_matrix));
    let rolled = ROTATED.replace(
        "quaternions = [[0.6, 0, 0.8, 0], [0.5, 0.5, 0.5, 0.5]]",
        "rolling = [0.3, -0.2, 0.5], radius = 2, angle = \"arc\"",
    );
    let m = rolling_ball::<4>(&[0.3, -0.2, 0.5], 2.0, RollingAngle::Arc);
    let by_matrix = ROTATED.replace(
        "{ rotate = { quaternions = [[0.6, 0, 0.8, 0], [0.5, 0.5, 0.5, 0.5]] } }",
        &matrix_toml(&m),
    );
    assert_same_vertices(&vertices(&rolled), &vertices(&by_matrix));
    // The default angle is the course's c = R/D.
    let course = rolled.replace(", angle = \"arc\"", "");
    let m = rolling_ball::<4>(&[0.3, -0.2, 0.5], 2.0, RollingAngle::Course);
    let by_matrix = ROTATED.replace(
        "{ rotate = { quaternions = [[0.6, 0, 0.8, 0], [0.5, 0.5, 0.5, 0.5]] } }",
        &matrix_toml(&m),
    );
    assert_same_vertices(&vertices(&course), &vertices(&by_matrix));
    // Every form survives the TOML round trip.
    for text in [ROTATED.to_string(), rolled, course] {
        let (desc, _) = load_toml_str(&text, "a.toml", None).unwrap();
        let (again, _) = load_toml_str(&to_toml(&desc).unwrap(), "b.toml", None).unwrap();
        assert_eq!(desc, again);
    }
}

#[test]
fn rotate_errors_name_the_field_and_its_place() {
    let bad = ROTATED.replace("[0.5, 0.5, 0.5, 0.5]", "[1, 0.75, 0, 0]");
    let line = bad.lines().position(|l| l.contains("[1, 0.75")).unwrap() + 1;
    let col = bad.lines().nth(line - 1).unwrap().find("[1, 0.75").unwrap() + 1;
    assert_eq!(
            load_error(&bad),
            format!(
                "scene.toml:{line}:{col}: objects[0].transform[1].rotate.quaternions[1]: not a unit quaternion (|p| = 1.25)"
            )
        );
    const STEP: &str = "{ rotate = { quaternions = [[0.6, 0, 0.8, 0], [0.5, 0.5, 0.5, 0.5]] } }";
    let cases: [(&str, &str, &[&str]); 9] = [
            ("[0.6, 0, 0.8, 0]", "[0.6, 0, 0.8]", &["rotate.quaternions[0]: expected 4 numbers"]),
            ("quaternions = [[0.6, 0, 0.8, 0], ", "quaternions = [", &["rotate.quaternions: expected [q, p]"]),
            ("] } }", "], plane = [0, 1], degrees = 3 } }", &["objects[0].transform[1].rotate.quaternions: give only one of plane, quaternions or rolling"]),
            ("] } }", "], radius = 1 } }", &["rotate.radius: \"radius\" goes with rolling, not with quaternions"]),
            (STEP, "{ rotate = { plane = [0, 1] } }", &["objects[0].transform[1].rotate: plane needs degrees"]),
            (STEP, "{ rotate = { rolling = [1, 2] , radius = 1 } }", &["rotate.rolling: expected N − 1 = 3 numbers (dim = 4), got 2"]),
            (STEP, "{ rotate = { rolling = [1, 2, 3] , radius = -1 } }", &["rotate.radius: must be a positive number, got -1"]),
            (STEP, "{ rotate = { rolling = [1, 2, 3] , radius = 1, angle = \"arcs\" } }", &["rotate.angle", "did you mean \"arc\""]),
            (STEP, "{ rotate = { } }", &["rotate: give one of plane"]),
        ];
    for (from, to, wants) in cases {
        let e = load_error(&ROTATED.replace(from, to));
        for want in wants {
            assert!(e.contains(want), "{to}: {e}");
        }
    }
    let three = ROTATED
        .replace("dim = 4", "dim = 3")
        .replace("[0, 0, 0, 5]", "[0, 0, 5]")
        .replace("look_at = [0, 0, 0, 0]", "look_at = [0, 0, 0]")
        .replace("up = [[0, 1, 0, 0], [0, 0, 1, 0]]", "up = [[0, 1, 0]]");
    let e = load_error(&three);
    assert!(
        e.contains("rotate.quaternions: quaternions = [q, p] give a 4D rotation, but dim = 3"),
        "{e}"
    );
}
