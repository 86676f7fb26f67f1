use crate::scene::*;
use crate::with_scene;
use std::sync::Arc;

/// The bits of a scene's retina: colour, depth, normals, object and primitive ids.
type Bits = (Vec<u32>, Vec<u32>, Vec<u32>, Vec<i32>, Vec<i64>);

/// The [`Bits`] of the retina `s` traces.
fn retina_bits(s: &AnyScene) -> Bits {
    let r = with_scene!(s, s, _N => crate::render::trace(s, &Default::default()).unwrap());
    let f = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    (
        f(&r.rgba),
        f(&r.depth),
        f(&r.normal),
        r.object_id,
        r.primitive_id,
    )
}

#[test]
fn camera_frames_share_the_bvh_and_trace_as_the_frames_built_anew() {
    let text = |target: &str, extra: &str| {
        format!(
            "dim = 4\n[camera]\nposition = [0.6, 0.9, 1.3, 3.5]\nlook_at = [0, 0, 0, 0]\n\
                 up = [[0, 1, 0, 0], [0, 0, 1, 0]]\nfov = 50\nresolution = [14, 12, 10]\n\
                 [[lights]]\ntype = \"point\"\nposition = [2, 2, 1, 2]\n\
                 [[objects]]\nshape = \"hypercube\"\ntransform = [{{ scale = 0.6 }}]\n\
                 [[objects]]\nshape = \"sphere\"\nsubdivisions = 2\n\
                 transform = [{{ scale = 0.3 }}, {{ translate = [0.5, 0.4, 0.2, 0.3] }}]\n\
                 [render]\nsamples = 2\nshadows = true\ncull_backfaces = true\n{extra}\
                 [animation]\nframes = 4\ntarget = {target}\n\
                 sweep = {{ plane = [0, 3], degrees = [0, 120] }}\n"
        )
    };
    let (desc, scene) = load_toml_str(&text("\"camera\"", ""), "cam.toml", None).unwrap();
    let bits = retina_bits;
    let mut frames = Vec::new();
    for k in 0..4 {
        let (frame, shared) = reused_frame(&desc, &scene, k, "cam.toml").unwrap().unwrap();
        assert_eq!(frame, animation_frame(&desc, k, "cam.toml").unwrap());
        let built = build_any(&frame, None, None).unwrap();
        let traced = bits(&shared);
        assert_eq!(traced, bits(&built), "frame {k}");
        match (&scene, &shared) {
            (AnyScene::D4(a), AnyScene::D4(b)) => {
                assert!(
                    (a.instances.trees().iter().zip(b.instances.trees()))
                        .all(|(x, y)| Arc::ptr_eq(x, y))
                        && Arc::ptr_eq(&a.objects, &b.objects)
                )
            }
            _ => panic!("dim 4"),
        }
        frames.push(traced);
    }
    // The camera moves: the frames differ.
    assert!(frames[1..].iter().all(|f| *f != frames[0]));
    // Frames that do not exist are refused.
    let err = reused_frame(&desc, &scene, 4, "cam.toml")
        .unwrap()
        .err()
        .unwrap()
        .to_string();
    assert!(err.contains("animation.frames"), "{err}");
}

#[test]
fn another_animation_table_shares_the_build() {
    let text = "dim = 4\n[camera]\nposition = [0.6, 0.9, 1.3, 3.5]\nlook_at = [0, 0, 0, 0]\n\
                    up = [[0, 1, 0, 0], [0, 0, 1, 0]]\nfov = 50\nresolution = 8\n\
                    [[objects]]\nshape = \"hypercube\"\n";
    let (old, built) = load_toml_str(text, "a.toml", None).unwrap();
    let mut desc = old.clone();
    let table =
        "[animation]\nframes = 5\ntarget = [0]\nsweep = { plane = [0, 3], degrees = [0, 90] }\n";
    desc.animation = load_toml_str(&format!("{text}{table}"), "a.toml", None)
        .unwrap()
        .0
        .animation;
    let shared = reanimated(&desc, &old, &built, "a.toml").unwrap().unwrap();
    match (&built, &shared) {
        (AnyScene::D4(a), AnyScene::D4(b)) => {
            assert!(
                (a.instances.trees().iter().zip(b.instances.trees()))
                    .all(|(x, y)| Arc::ptr_eq(x, y))
                    && Arc::ptr_eq(&a.objects, &b.objects)
            )
        }
        _ => panic!("dim 4"),
    }
    assert_eq!(
        retina_bits(&shared),
        retina_bits(&build_any(&desc, None, None).unwrap())
    );
    // The table is checked as a build checks it.
    let mut bad = desc.clone();
    bad.animation.as_mut().unwrap().target = desc::AnimationTarget::Objects(vec![3]);
    let err = reanimated(&bad, &old, &built, "a.toml")
        .unwrap()
        .err()
        .unwrap();
    let want = build_desc(&bad, "a.toml", None).err().unwrap().to_string();
    assert_eq!(err.to_string(), want);
    assert!(want.contains("animation.target[0]"), "{want}");
    // Anything else changed, or an object read from a file: build anew.
    let mut other = desc.clone();
    other.camera.fov = Some(40.0);
    assert!(reanimated(&other, &old, &built, "a.toml").is_none());
    let mut filed = old.clone();
    filed.objects[0].file = Some("cube.npz".into());
    assert!(reanimated(&filed, &filed, &built, "a.toml").is_none());
}

#[test]
fn object_frames_share_the_bvh_and_trace_as_the_frames_built_anew() {
    // Frames of an animation that moves objects: the base scene's trees reached through
    // the frames' transforms (flat cells included, in 5D) trace bit for bit as the
    // frame's own build; shadows, convexity certificates and culling included; the whole
    // scene, or one object; objects in their own tree or sharing the untransformed
    // objects' tree (with `scaled = false` the hypercube has no transform of its own), a
    // transform that reverses handedness (`mirror`).
    fn check<const N: usize>(target: &str, scaled: bool, mirror: bool, instance_min: usize) {
        let axis = crate::testutil::unit_toml::<N>;
        let up: Vec<String> = (1..N - 1).map(|k| axis(k, 1.0)).collect();
        let position: Vec<String> = (0..N)
            .map(|i| format!("{:?}", 0.6 + 0.3 * i as f64))
            .collect();
        let text = format!(
                "dim = {N}\n[camera]\nposition = [{}]\nlook_at = {}\nup = [{}]\nfov = 50\n\
                 resolution = {}\n[[lights]]\ntype = \"point\"\nposition = {}\n\
                 [[objects]]\nshape = \"hypercube\"\n{}\
                 [[objects]]\nshape = \"sphere\"\nsubdivisions = 1\nmaterial = {{ smooth = true }}\n\
                 transform = [{{ scale = 0.3 }}, {{ translate = {} }}]\n\
                 [[objects]]\nshape = \"mesh\"\nvertices = [{}]\nsimplices = [[0, 0, {}]]\n\
                 [render]\nsamples = 2\nshadows = true\ncull_backfaces = true\n\
                 [animation]\nframes = 4\ntarget = {target}\n\
                 sweep = {{ plane = [0, {}], degrees = [0, 120] }}\n",
                position.join(", "),
                axis(0, 0.0),
                up.join(", "),
                if N == 4 { 12 } else { 6 },
                axis(N - 1, 2.0),
                match (scaled, mirror) {
                    (false, _) => String::new(),
                    (true, false) => "transform = [{ scale = 0.6 }]\n".into(),
                    (true, true) => format!(
                        "transform = [{{ scale = [-0.6{}] }}]\n",
                        ", 0.6".repeat(N - 1)
                    ),
                },
                axis(0, 0.7),
                (0..N).map(|k| axis(k, 1.0 + k as f64)).collect::<Vec<_>>().join(", "),
                (1..N - 1).map(|k| k.to_string()).collect::<Vec<_>>().join(", "),
                N - 1
            );
        let (desc, _) = load_toml_str(&text, "obj.toml", None).unwrap();
        let build = |d: &SceneDesc| {
            let morton = crate::accel::MORTON_MIN;
            with_dim!(d.dim, M => {
                let s = crate::scene::build::build_using::<M>(d, None, None, (morton, instance_min));
                <Scene<M> as IntoAny>::into_any(s.unwrap())
            })
            .unwrap()
        };
        let scene = build(&desc);
        // The base scene's feature edges: the frames share its objects' ridges, and keep
        // the edges of the objects they do not move.
        let unmoved: Vec<usize> = match target {
            "[1]" => vec![0, 2],
            "[0]" => vec![1, 2],
            _ => vec![],
        };
        let ridges = with_scene!(&scene, s, _N => {
            crate::edges::edge_segments(s, 20.0).unwrap();
            s.edge_cache.contents().1
        });
        assert_eq!(ridges.len(), 3);
        let bits = retina_bits;
        let mut frames = Vec::new();
        for k in 0..4 {
            let (frame, reused) = reused_frame(&desc, &scene, k, "obj.toml").unwrap().unwrap();
            let built = build(&frame);
            // The frame traces the base scene's trees (none is changed); objects traced in
            // world space (fewer than `instance_min` simplices) get a tree built anew
            // when one of them moves.
            with_scene!(&scene, a, _N => with_scene!(&reused, b, _M => {
                for o in 0..3 {
                    let (x, y) = (a.instances.tree(o), b.instances.tree(o));
                    let own = a.objects[o].mesh.simplices.len() >= instance_min;
                    let same = std::ptr::addr_eq(Arc::as_ptr(x), Arc::as_ptr(y));
                    assert_eq!(same, own || k == 0, "N={N} {target} frame {k} object {o}");
                }
            }));
            let traced = bits(&reused);
            assert_eq!(traced, bits(&built), "N={N} {target} frame {k}");
            // Frame 0 turns by 0°: every object keeps its vertices and its edges.
            let kept = if k == 0 {
                vec![0, 1, 2]
            } else {
                unmoved.clone()
            };
            match (&reused, &built) {
                (AnyScene::D4(a), AnyScene::D4(b)) => check_same(a, b, &kept, &ridges),
                (AnyScene::D5(a), AnyScene::D5(b)) => check_same(a, b, &kept, &ridges),
                _ => panic!("dim"),
            }
            frames.push(traced);
        }
        assert!(
            frames[1..].iter().all(|f| *f != frames[0]),
            "the objects move"
        );
    }
    fn check_same<const N: usize>(
        reused: &Scene<N>,
        built: &Scene<N>,
        unmoved: &[usize],
        ridges: &[(usize, usize)],
    ) {
        // Feature edges from the shared ridges (none found again) and the moved
        // vertices: bit for bit those of the frame built anew.
        assert_eq!(
            reused.edge_cache.contents(),
            (unmoved.to_vec(), ridges.to_vec())
        );
        let edges = crate::edges::edge_segments(reused, 20.0).unwrap();
        assert_eq!(edges, crate::edges::edge_segments(built, 20.0).unwrap());
        assert!(edges.iter().any(|e| e.object == 0) && edges.iter().any(|e| e.object == 1));
        assert_eq!(reused.edge_cache.contents().1, ridges, "the ridges fit");
        assert_eq!(reused.instances.cell_count(), built.instances.cell_count());
        assert_eq!(reused.extent.to_bits(), built.extent.to_bits());
        assert_eq!(reused.skipped_degenerate, built.skipped_degenerate);
        reused.find_certificates();
        built.find_certificates();
        for (a, b) in reused.objects.iter().zip(built.objects.iter()) {
            assert_eq!(a.convex.get(), b.convex.get());
            assert_eq!(a.mesh, b.mesh);
        }
        for g in 0..built.simplex_count() as u32 {
            assert_eq!(reused.flat_normal(g), built.flat_normal(g));
        }
    }
    for min in [1, crate::accel::INSTANCE_MIN] {
        check::<4>("\"objects\"", true, false, min);
        check::<4>("[1]", true, false, min);
        check::<4>("[0]", false, false, min);
        check::<4>("\"objects\"", true, true, min);
        check::<5>("\"objects\"", true, false, min);
    }
}

#[test]
fn frames_moving_small_objects_beside_a_large_one_trace_as_built_anew() {
    // A large untransformed sphere (24,576 tetrahedra) and a small hypercube share the
    // world-space tree; frames that move the hypercube give it a tree built anew, and the
    // shared tree's stale copy of it must not be seen; with "objects" the sphere is
    // traced through its map in the same tree.
    for target in ["[1]", "\"objects\""] {
        let text = format!(
            "dim = 4\n[camera]\nposition = [0.6, 0.9, 1.3, 3.5]\nlook_at = [0, 0, 0, 0]\n\
                 up = [[0, 1, 0, 0], [0, 0, 1, 0]]\nfov = 50\nresolution = 14\n\
                 [[lights]]\ntype = \"point\"\nposition = [2, 2, 1, 2]\n\
                 [[objects]]\nshape = \"sphere\"\nsubdivisions = 3\n\
                 [[objects]]\nshape = \"hypercube\"\n\
                 transform = [{{ scale = 0.3 }}, {{ translate = [0.9, 0.2, 0.3, 0.5] }}]\n\
                 [render]\nshadows = true\n\
                 [animation]\nframes = 3\ntarget = {target}\n\
                 sweep = {{ plane = [0, 3], degrees = [0, 90] }}\n"
        );
        let (desc, scene) = load_toml_str(&text, "mix.toml", None).unwrap();
        for k in 0..3 {
            let (frame, reused) = reused_frame(&desc, &scene, k, "mix.toml").unwrap().unwrap();
            let built = build_any(&frame, None, None).unwrap();
            assert_eq!(
                retina_bits(&reused),
                retina_bits(&built),
                "{target} frame {k}"
            );
            if let (AnyScene::D4(a), AnyScene::D4(b)) = (&reused, &built) {
                assert_eq!(a.instances.len(), b.instances.len());
                assert_eq!(a.skipped_degenerate, b.skipped_degenerate);
            }
        }
    }
}

#[test]
fn objects_in_their_own_space_trace_as_their_meshes_moved_into_world_space() {
    // Independent reference: each transformed object given instead as a mesh of its
    // world-space vertices (no transform: traced as before instancing, in world space).
    // Shear, reflection, non-uniform scale and translation, with shadows and culling.
    fn check<const N: usize>() {
        let axis = crate::testutil::unit_toml::<N>;
        let list = |v: Vec<String>| v.join(", ");
        let up = list((1..N - 1).map(|k| axis(k, 1.0)).collect());
        let position = list(
            (0..N)
                .map(|i| format!("{:?}", 0.7 + 0.4 * i as f64))
                .collect(),
        );
        let head = format!(
            "dim = {N}\n[camera]\nposition = [{position}]\nlook_at = {}\nup = [{up}]\n\
                 fov = 45\nresolution = {}\n[[lights]]\ntype = \"point\"\nposition = [{}]\n\
                 [render]\nshadows = true\ncull_backfaces = true\n",
            axis(0, 0.0),
            if N == 3 {
                48
            } else if N == 4 {
                20
            } else {
                8
            },
            list(
                (0..N)
                    .map(|i| format!("{:?}", 2.0 - 0.5 * i as f64))
                    .collect()
            ),
        );
        // A hypercube sheared and mirrored, and a sphere mirrored, squashed and moved in front
        // of it.
        let shear = list(
            (0..N)
                .map(|i| {
                    let row = (0..N).map(|j| {
                        let x = match j {
                            _ if i == j => [-0.5, 0.5][i.min(1)],
                            _ if j == i + 1 => 0.2,
                            _ => 0.0,
                        };
                        format!("{x:?}")
                    });
                    format!("[{}]", row.collect::<Vec<_>>().join(", "))
                })
                .collect(),
        );
        let squash = list(
            (0..N)
                .map(|i| format!("{:?}", [-0.3, 0.4, 0.25][i % 3]))
                .collect(),
        );
        let moved = format!(
            "[[objects]]\nshape = \"hypercube\"\ntransform = [{{ matrix = [{shear}] }}]\n\
                 [[objects]]\nshape = \"sphere\"\nsubdivisions = 1\n\
                 transform = [{{ scale = [{squash}] }}, {{ translate = [{}] }}]\n",
            list(
                (0..N)
                    .map(|i| format!("{:?}", 0.35 + 0.1 * i as f64))
                    .collect()
            ),
        );
        let parse = |text: &str| {
            let (desc, _) = load_toml_str(text, "t.toml", None).unwrap();
            let morton = crate::accel::MORTON_MIN;
            crate::scene::build::build_using::<N>(&desc, None, None, (morton, 1)).unwrap()
        };
        let s = &parse(&format!("{head}{moved}"));
        // The reference: the world-space meshes (simplices in the order the build gave
        // them, mirrored ones swapped) as untransformed mesh objects.
        let mut world = head.clone();
        for o in s.objects.iter() {
            let v: Vec<String> = o.mesh.vertices.iter().map(|v| format!("{v:?}")).collect();
            let t: Vec<String> = o.mesh.simplices.iter().map(|t| format!("{t:?}")).collect();
            world += &format!(
                "[[objects]]\nshape = \"mesh\"\nvertices = [{}]\nsimplices = [{}]\n",
                v.join(", "),
                t.join(", ")
            );
        }
        let w = &parse(&world);
        assert_eq!(
            s.instances.instance_count(),
            2,
            "N={N}: each object in its own space"
        );
        assert_eq!(w.instances.instance_count(), 1);
        // The mirrored, sheared hypercube is known convex, its certificate found in its own
        // space (the reference's mesh of coplanar simplices need not pass); the sphere's is
        // the reference's.
        s.find_certificates();
        w.find_certificates();
        assert_eq!(
            s.objects[0].convex.get(),
            Some(true),
            "N={N}: the hypercube's certificate"
        );
        assert_eq!(
            s.objects[1].convex.get(),
            w.objects[1].convex.get(),
            "N={N}: the sphere's"
        );
        for g in 0..s.simplex_count() as u32 {
            let (a, b) = (s.flat_normal(g), w.flat_normal(g));
            let d = (0..N).map(|i| (a[i] - b[i]).abs()).fold(0.0, f64::max);
            // (Each rounded to f32 in its own space.)
            assert!(d < 1e-6, "N={N} simplex {g}: normals {a:?} and {b:?}");
        }
        let opts = Default::default();
        let a = crate::render::trace(s, &opts).unwrap();
        let b = crate::render::trace(w, &opts).unwrap();
        let cells = a.object_id.len();
        let same: Vec<usize> = (0..cells)
            .filter(|&c| a.object_id[c] == b.object_id[c] && a.primitive_id[c] == b.primitive_id[c])
            .collect();
        assert!(
            same.len() as f64 >= 0.99 * cells as f64,
            "N={N}: {} of {cells} cells hit the same simplex",
            same.len()
        );
        let hits = same.iter().filter(|&&c| a.object_id[c] >= 0).count();
        assert!(
            hits >= 50,
            "N={N}: the objects fill {hits} of {cells} cells"
        );
        let mut shaded_apart = 0;
        for &c in &same {
            let close = |x: f32, y: f32, tol: f32| (x - y).abs() <= tol * (1.0 + x.abs());
            if a.object_id[c] >= 0 {
                assert!(close(a.depth[c], b.depth[c], 1e-5), "N={N} cell {c}: depth");
            }
            for i in 0..N {
                assert!(close(a.normal[c * N + i], b.normal[c * N + i], 1e-5));
            }
            // A shadow ray grazing an edge may decide otherwise.
            if (0..4).any(|k| !close(a.rgba[c * 4 + k], b.rgba[c * 4 + k], 1e-4)) {
                shaded_apart += 1;
            }
        }
        assert!(
            shaded_apart * 100 <= cells,
            "N={N}: {shaded_apart} cells shaded apart"
        );
    }
    check::<3>();
    check::<4>();
    check::<5>();
}
