use super::*;
use crate::testutil::load_error;

/// The boundary of the regular N-simplex seen from +x_N, in dimension `dim`.
fn simplex_scene(dim: usize) -> String {
    let axis = |k: usize, x: f64| -> String {
        let e: Vec<String> = (0..dim)
            .map(|i| if i == k { x.to_string() } else { "0".into() })
            .collect();
        format!("[{}]", e.join(", "))
    };
    let up: Vec<String> = (1..dim - 1).map(|k| axis(k, 1.0)).collect();
    format!(
        "dim = {dim}\n[camera]\nposition = {}\nlook_at = {}\nup = [{}]\nfov = 40\n\
             resolution = 2\n[[objects]]\nshape = \"simplex\"\n",
        axis(dim - 1, 4.0),
        axis(0, 0.0),
        up.join(", ")
    )
}

#[test]
fn every_supported_dimension_has_its_scene_variant() {
    for &d in crate::dim::SUPPORTED_DIMS {
        let (_, scene) = load_toml_str(&simplex_scene(d), "simplex.toml", None).unwrap();
        assert_eq!(scene.dim(), d);
        // `with_scene!` binds the Scene<N> of the variant with N = d: its vectors have d
        // coordinates, and the simplex's boundary d + 1 facets.
        let (n, coords, facets) =
            with_scene!(&scene, s, N => (N, s.camera.position.len(), s.instances.len()));
        assert_eq!((n, coords, facets), (d, d, d + 1));
        // And back: the scene taken out of the enum goes into the same variant.
        let again = with_scene!(scene, s, _N => s.into_any());
        assert_eq!(again.dim(), d);
    }
    let e = load_error(&simplex_scene(3).replace("dim = 3", "dim = 9"));
    assert!(e.contains("dim must be in 2..=8"), "{e}");
}

const CUBE: &str = r#"
dim = 4
[camera]
position = [0, 0, 0, 5]
look_at = [0, 0, 0, 0]
up = [[0, 1, 0, 0], [0, 0, 1, 0]]
fov = 40
resolution = [8, 6, 4]

[[lights]]
type = "point"
position = [1, 2, 3, 4]
falloff = 3

[[objects]]
shape = "hypercube"
material = { color = [1, 0.5, 0.25], specular = [0.1, 0.2, 0.3], smooth = true }
transform = [{ scale = 0.5 }, { rotate = { plane = [0, 3], degrees = 30 } }, { translate = [0, 0, 0.5, 0] }]

[[objects]]
shape = "mesh"
vertices = [[0, 0, 0, 0], [1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0]]
simplices = [[0, 1, 2, 3]]
"#;

#[test]
fn toml_round_trips_through_the_description() {
    let (desc, scene) = load_toml_str(CUBE, "cube.toml", None).unwrap();
    assert_eq!(scene.dim(), 4);
    let text = to_toml(&desc).unwrap();
    let (again, _) = load_toml_str(&text, "again.toml", None).unwrap();
    assert_eq!(desc, again);
    with_scene!(&scene, s, N => {
        assert_eq!(N, 4);
        assert_eq!(s.camera.numpy_shape(), vec![4, 6, 8]);
        assert_eq!(s.instances.len(), 48 + 1);
        assert_eq!(s.locate(48), (1, 0));
        assert_eq!(s.locate(47), (0, 47));
    });
}

#[test]
fn errors_name_file_line_column_and_field() {
    let bad = CUBE.replace("color = [1, 0.5, 0.25]", "color = [1, 0.5]");
    let line = bad
        .lines()
        .position(|l| l.contains("color = [1, 0.5]"))
        .unwrap()
        + 1;
    let col = bad.lines().nth(line - 1).unwrap().find("[1, 0.5]").unwrap() + 1;
    assert_eq!(
        load_error(&bad),
        format!("scene.toml:{line}:{col}: objects[0].material.color: expected 3 numbers, got 2")
    );
    let e = load_error(&CUBE.replace("shape = \"hypercube\"", "shape = \"hypercub\""));
    assert!(
        e.contains("objects[0].shape: unknown shape \"hypercub\" (did you mean \"hypercube\"?)"),
        "{e}"
    );
    let e = load_error(&CUBE.replace("falloff = 3", "falof = 3"));
    assert!(
        e.contains("lights[0]") && e.contains("did you mean \"falloff\""),
        "{e}"
    );
    let e = load_error(&CUBE.replace("simplices = [[0, 1, 2, 3]]", "simplices = [[0, 1, 2, 4]]"));
    assert!(
        e.contains("objects[1].simplices[0][3]: vertex index 4 out of range"),
        "{e}"
    );
    let e = load_error(&CUBE.replace("dim = 4", "dim = 9"));
    assert!(e.contains("dim") && e.contains("2..=8"), "{e}");
    let e = load_error(&CUBE.replace("resolution = [8, 6, 4]", "resolution = [8, 0, 4]"));
    assert!(
        e.contains("camera.resolution: axis 2 has zero cells"),
        "{e}"
    );
    let e = load_error(&CUBE.replace("resolution = [8, 6, 4]", "resolution = 100000000"));
    assert!(e.contains("camera.resolution") && e.contains("iB"), "{e}");
    let e = load_error(&CUBE.replace(
        "[[objects]]\nshape = \"mesh\"",
        "[[objects]]\nshape = \"mesh\"\nx = ]",
    ));
    assert!(e.starts_with("scene.toml:"), "{e}");
}

#[test]
fn an_array_field_is_the_inline_field_with_the_same_values() {
    let text = "dim = 4\n[camera]\nposition = [0.6, 0.8, 1.0, 3.0]\nlook_at = [0, 0, 0, 0]\n\
                    up = [[0, 1, 0, 0], [0, 0, 1, 0]]\nfov = 50\nresolution = 6\n[[objects]]\n\
                    shape = \"elevation\"\nfield = [[[0, 1, 2], [1, 0, 3]], [[2, 2, 0], [0.5, 1, 1]]]\n";
    let (inline, built) = load_toml_str(text, "f.toml", None).unwrap();
    let values = vec![0.0, 1.0, 2.0, 1.0, 0.0, 3.0, 2.0, 2.0, 0.0, 0.5, 1.0, 1.0];
    let mut array = inline.clone();
    array.objects[0].field = Some(desc::FieldDesc::Array(
        desc::Grid::new([2, 2, 3], values.clone()).unwrap(),
    ));
    assert_eq!(array, inline);
    assert_eq!(inline, array);
    assert_eq!(to_toml(&array).unwrap(), to_toml(&inline).unwrap());
    let mut other = values;
    other[4] = 0.25;
    let mut changed = inline.clone();
    changed.objects[0].field = Some(desc::FieldDesc::Array(
        desc::Grid::new([2, 2, 3], other).unwrap(),
    ));
    assert!(changed != inline && changed != array);
    assert!(desc::Grid::new([2, 2, 2], vec![0.0; 7]).is_none());
    assert!(desc::Grid::new([1 << 40, 1 << 40, 0], vec![]).is_none());
    // Masked (NaN) values equal themselves, in copies and across the two forms.
    let mut masked = inline.clone();
    if let Some(desc::FieldDesc::Inline(x)) = &mut masked.objects[0].field {
        x[1][0][2] = f64::NAN;
    }
    let mut masked_array = masked.clone();
    let mut v = vec![0.0, 1.0, 2.0, 1.0, 0.0, 3.0, 2.0, 2.0, 0.0, 0.5, 1.0, 1.0];
    v[8] = f64::NAN;
    masked_array.objects[0].field = Some(desc::FieldDesc::Array(
        desc::Grid::new([2, 2, 3], v).unwrap(),
    ));
    assert_eq!(masked_array, masked_array.clone());
    assert_eq!(masked_array, masked);
    assert_ne!(masked_array, inline);
    // Empty axes write as empty lists (the build refuses them; writing must not panic).
    let empty = desc::Grid::new([2, 0, 3], vec![]).unwrap();
    let mut text_empty = inline.clone();
    text_empty.objects[0].field = Some(desc::FieldDesc::Array(empty));
    assert!(to_toml(&text_empty).unwrap().contains("field = [[], []]"));
    let from_array = build_desc(&array, "f", None).unwrap();
    let depth = |s: &AnyScene| with_scene!(s, s, _N => crate::render::trace(s, &Default::default()).unwrap().depth);
    assert_eq!(depth(&from_array), depth(&built));
}

#[test]
fn array_meshes_build_as_their_inline_lists_and_errors_name_the_row() {
    let text = "dim = 3\n[camera]\nposition = [0.5, 0.7, 3.0]\nlook_at = [0, 0, 0]\n\
                    up = [0, 1, 0]\nfov = 50\nresolution = 8\n[[objects]]\nshape = \"mesh\"\n\
                    vertices = [[-1, -1, 0], [1, -1, 0], [0, 1, 0], [0, 0, 1]]\n\
                    simplices = [[0, 1, 2], [0, 1, 3], [1, 2, 3], [2, 0, 3]]\n\
                    values = [0, 1, 2, 3]\nmaterial = { colormap = \"viridis\" }\n";
    let (inline, built) = load_toml_str(text, "m.toml", None).unwrap();
    let v = vec![
        -1.0, -1.0, 0.0, 1.0, -1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0,
    ];
    let s = vec![0i64, 1, 2, 0, 1, 3, 1, 2, 3, 2, 0, 3];
    let with = |v: Vec<f64>, width: usize, s: Vec<i64>| {
        let mut d = inline.clone();
        d.objects[0].vertices = Some(desc::Rows::Array(desc::Table::new(width, v).unwrap()));
        d.objects[0].simplices = Some(desc::Rows::Array(desc::Table::new(3, s).unwrap()));
        d.objects[0].values = Some(desc::Column::Array(vec![0.0, 1.0, 2.0, 3.0].into()));
        d
    };
    let array = with(v.clone(), 3, s.clone());
    assert_eq!(array, inline);
    assert_eq!(inline, array);
    assert_eq!(to_toml(&array).unwrap(), to_toml(&inline).unwrap());
    let from_array = build_desc(&array, "m", None).unwrap();
    let trace = |s: &AnyScene| {
        with_scene!(s, s, _N => {
            let r = crate::render::trace(s, &Default::default()).unwrap();
            (r.depth, r.rgba)
        })
    };
    let (d0, c0) = trace(&built);
    assert!(d0.iter().any(|d| d.is_finite()));
    assert_eq!((d0, c0), trace(&from_array));
    // A changed coordinate differs; errors name the element, as for lists.
    let mut moved = v.clone();
    moved[11] = 0.5;
    assert_ne!(with(moved, 3, s.clone()), inline);
    let err = |d: &SceneDesc| build_desc(d, "m", None).err().unwrap().to_string();
    let mut out_of_range = s.clone();
    out_of_range[7] = 4;
    assert!(err(&with(v.clone(), 3, out_of_range))
        .contains("objects[0].simplices[2][1]: vertex index 4 out of range"),);
    let mut nan = v.clone();
    nan[4] = f64::NAN;
    assert!(err(&with(nan, 3, s.clone())).contains("objects[0].vertices[1][1]: non-finite"));
    let wide = with(vec![0.0; 8], 4, s);
    assert!(err(&wide).contains("objects[0].vertices[0]: expected 3 numbers (dim = 3), got 4"));
}

/// The exact normals of `mesh`'s simplices (zero for a degenerate one), as the certificates
/// are found from.
fn exact_normals<const N: usize>(mesh: &crate::mesh::Mesh<N>) -> Vec<crate::linalg::Vector<N>> {
    (0..mesh.simplices.len())
        .map(|s| {
            crate::geometry::hyperplane(&mesh.simplex_points(s)).map_or([0.0; N], |h| h.normal)
        })
        .collect()
}

#[test]
fn convexity_certificates_are_found_at_the_first_lit_trace_as_convex_side_finds_them() {
    // 4D: (a) the cross-polytope's boundary given as a mesh (not known convex: every step of
    // `convex_side`) held in world space, (b) the same mirrored (a map that reverses
    // handedness) and held in its own space, a mirrored hypercube likewise (known convex),
    // (c) the mesh with a vertex pushed through its middle (a dent: not convex), (d) an elevation map (never certified); with the SAH
    // and the Morton builds. The build finds none; a trace finds them, once.
    let mesh = |dent: f64| {
        let mut m = crate::shapes::cross_polytope::<4>();
        m.vertices[0] = crate::linalg::scale(&m.vertices[0], dent);
        let rows = |v: Vec<String>| format!("[{}]", v.join(", "));
        format!(
            "[[objects]]\nshape = \"mesh\"\nvertices = {}\nsimplices = {}\n",
            rows(m.vertices.iter().map(|v| format!("{v:?}")).collect()),
            rows(m.simplices.iter().map(|s| format!("{s:?}")).collect()),
        )
    };
    let text = |lights: &str| {
        format!(
            "dim = 4\n[camera]\nposition = [0.6, 0.9, 1.3, 3.5]\nlook_at = [0, 0, 0, 0]\n\
             up = [[0, 1, 0, 0], [0, 0, 1, 0]]\nfov = 50\nresolution = 6\n{lights}{}{}\
             transform = [{{ scale = [-0.4, 0.4, 0.5, 0.4] }}, {{ translate = [0.8, 0, 0, 0] }}]\n\
             [[objects]]\nshape = \"hypercube\"\n\
             transform = [{{ scale = [0.3, -0.3, 0.2, 0.3] }}, {{ translate = [-0.8, 0, 0, 0] }}]\n\
             {}transform = [{{ translate = [0.0, -0.8, 0.0, 0.0] }}]\n\
             [[objects]]\nshape = \"elevation\"\n\
             field = [[[0.0, 0.3], [0.2, 0.9]], [[0.1, 0.5], [0.4, 1.0]]]\nheight = 0.6\n\
             [render]\nshadows = true\n",
            mesh(1.0),
            mesh(1.0),
            mesh(-0.5),
        )
    };
    let light = "[[lights]]\ntype = \"point\"\nposition = [2, 2, 1, 2]\n";
    for morton_min in [crate::accel::MORTON_MIN, 0] {
        let build = |text: &str| {
            let (desc, _) = load_toml_str(text, "lazy.toml", None).unwrap();
            // Every transformed object held in its own space.
            build::build_using::<4>(&desc, None, None, (morton_min, 1)).unwrap()
        };
        let s = build(&text(light));
        assert_eq!(s.instances.instance_count(), 4, "objects 1, 2, 3 alone");
        assert!(s.instances.map(1).is_some_and(|m| m.flip));
        let pending: Vec<bool> = s.objects.iter().map(|o| o.convex.pending()).collect();
        assert_eq!(
            pending,
            [true, true, true, true, false],
            "the build finds none"
        );
        assert_eq!(s.objects[4].convex.get(), None, "(d) never certified");
        crate::render::trace(&s, &Default::default()).unwrap();
        assert!(
            s.objects.iter().all(|o| !o.convex.pending()),
            "the trace finds them"
        );
        // What `convex_side` finds on each world mesh (simplices in the order the mirror gave
        // them), the hypercube known convex.
        let side = |k: usize, known: bool| {
            let mesh = &s.objects[k].mesh;
            crate::convex::convex_side(mesh, &exact_normals(mesh), known)
        };
        let found: Vec<Option<bool>> = s.objects.iter().map(|o| o.convex.get()).collect();
        let expected = [
            side(0, false),
            side(1, false),
            side(2, true),
            side(3, false),
            None,
        ];
        assert_eq!(found, expected, "morton_min {morton_min}");
        assert_eq!(found[..4], [Some(true), Some(true), Some(true), None]);
        // A picture's probe finds them too.
        let p = build(&text(light));
        assert!(crate::render::probe::ScenePicture::new(&p).is_some());
        let found_p: Vec<Option<bool>> = p.objects.iter().map(|o| o.convex.get()).collect();
        assert_eq!(found_p, found);
        // (e) Without a light (or without shadows) none is ever to be found.
        for t in [
            text(""),
            text(light).replace("shadows = true", "shadows = false"),
        ] {
            let d = build(&t);
            assert!(d
                .objects
                .iter()
                .all(|o| !o.convex.pending() && o.convex.get().is_none()));
        }
    }
}
