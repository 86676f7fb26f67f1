use crate::scene::npz::Array2;
use crate::scene::{load_toml_str, load_toml_with, AnyScene, MeshReader};
use crate::shapes::simplex_boundary;
use crate::with_scene;
use std::path::Path;

/// Serves the boundary of the regular 3-simplex for any `.tet` file, and an error otherwise.
struct Tetrahedra;

impl MeshReader for Tetrahedra {
    fn read(&self, path: &Path, dim: usize) -> Result<[Array2; 2], String> {
        if path.extension().is_none_or(|e| e != "tet") || dim != 3 {
            return Err(format!("cannot read this (dim = {dim})"));
        }
        let m = simplex_boundary::<3>();
        Ok([
            Array2 {
                shape: (m.vertices.len(), 3),
                data: m.vertices.iter().flatten().copied().collect(),
                integer: false,
            },
            Array2 {
                shape: (m.simplices.len(), 3),
                data: m.simplices.iter().flatten().map(|&i| i as f64).collect(),
                integer: true,
            },
        ])
    }
}

fn scene(object: &str) -> String {
    format!(
            "dim = 3\n[camera]\nposition = [0, 0, 5]\nlook_at = [0, 0, 0]\nup = [0, 1, 0]\nfov = 40\nresolution = 4\n\n[[objects]]\nshape = \"mesh\"\n{object}\n"
        )
}

fn vertices(scene: &AnyScene) -> Vec<Vec<f64>> {
    with_scene!(scene, s, _N => s.objects[0].mesh.vertices.iter().map(|v| v.to_vec()).collect())
}

#[test]
fn other_formats_come_from_the_reader_and_errors_name_field_and_file() {
    let dir = std::env::temp_dir().join(format!("ndtrace-mesh-file-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("a.tet"), "").unwrap();
    std::fs::write(dir.join("b.obj"), "").unwrap();
    let text = scene("file = \"a.tet\"");
    let (_, s) = load_toml_with(&text, "s.toml", Some(&dir), Some(&Tetrahedra)).unwrap();
    let want: Vec<Vec<f64>> = simplex_boundary::<3>()
        .vertices
        .iter()
        .map(|v| v.to_vec())
        .collect();
    assert_eq!(vertices(&s), want);
    // Errors: the reader's, a missing file, no reader; each with line, column, field, file.
    let err = |t: &str, reader: Option<&dyn MeshReader>| {
        load_toml_with(t, "s.toml", Some(&dir), reader)
            .err()
            .unwrap()
            .to_string()
    };
    let full = |f: &str| dir.join(f).display().to_string();
    assert_eq!(
        err(&scene("file = \"b.obj\""), Some(&Tetrahedra)),
        format!(
            "s.toml:11:8: objects[0].file: {}: cannot read this (dim = 3)",
            full("b.obj")
        )
    );
    assert_eq!(
        err(&scene("file = \"c.obj\""), Some(&Tetrahedra)),
        format!(
            "s.toml:11:8: objects[0].file: cannot open {}: no such file",
            full("c.obj")
        )
    );
    let e = err(&scene("file = \"a.tet\""), None);
    assert!(
        e.starts_with("s.toml:11:8: objects[0].file: ") && e.contains("only .npz"),
        "{e}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn closed_meshes_with_inward_simplices_are_warned_about() {
    let tet = "vertices = [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]]\nsimplices = [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]";
    let (_, s) = load_toml_str(&scene(tet), "s.toml", None).unwrap();
    assert!(s.warnings().is_empty(), "{:?}", s.warnings());
    let flipped = tet.replace("[0, 1, 3]", "[1, 0, 3]");
    let (_, s) = load_toml_str(&scene(&flipped), "s.toml", None).unwrap();
    assert_eq!(
            s.warnings(),
            ["objects[0]: the closed mesh is not consistently oriented: 1 of its 4 simplices face inward (back-face culling drops them); ndtrace.mesh.orient(vertices, simplices) repairs it"]
        );
    // Open meshes are not checked; all-inward closed ones are consistent.
    let open = tet
        .replace(", [1, 2, 3]]", "]")
        .replace("[0, 1, 3]", "[1, 0, 3]");
    assert!(load_toml_str(&scene(&open), "s.toml", None)
        .unwrap()
        .1
        .warnings()
        .is_empty());
    let inward = tet
        .replace("[0, 2, 1]", "[0, 1, 2]")
        .replace("[0, 1, 3]", "[0, 3, 1]")
        .replace("[0, 3, 2]", "[0, 2, 3]")
        .replace("[1, 2, 3]", "[1, 3, 2]");
    assert!(load_toml_str(&scene(&inward), "s.toml", None)
        .unwrap()
        .1
        .warnings()
        .is_empty());
}
