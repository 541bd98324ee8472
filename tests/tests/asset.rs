//! Nothing is dropped silently (issue 49, item 6): what a glTF asset holds
//! besides its triangles is counted by `info --json` and, where an export
//! leaves it out, listed in `dropped` and on stderr; an extension the file
//! requires and lodstudio cannot read refuses it with exit 2, by name;
//! meshopt-compressed files are decoded.

use std::path::Path;

use lodstudio_tests::{lodstudio, lodstudio_json, shared_model};
use serde_json::{Value, json};

fn dropped_whats(j: &Value) -> Vec<String> {
    j["dropped"]
        .as_array()
        .expect("a dropped list")
        .iter()
        .map(|d| d["what"].as_str().expect("what").to_string())
        .collect()
}

/// One triangle in a glTF with its buffer inline, plus `extra` merged into
/// the root object.
fn triangle_gltf(dir: &Path, name: &str, extra: Value) -> String {
    let mut root = json!({
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
        "buffers": [{"byteLength": 36, "uri": "data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA"}],
        "bufferViews": [{"buffer": 0, "byteLength": 36}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                       "min": [0.0, 0.0, 0.0], "max": [1.0, 1.0, 0.0]}]
    });
    for (k, v) in extra.as_object().expect("an object") {
        root[k] = v.clone();
    }
    let path = dir.join(name);
    std::fs::write(&path, serde_json::to_vec(&root).unwrap()).unwrap();
    path.display().to_string()
}

/// `info --json` counts the scene: the engine's nodes, meshes and
/// instances; a skin and its animation; morph targets; extensions.
#[test]
fn info_counts_the_asset() {
    let engine = lodstudio_json(&[
        "info",
        shared_model("2CylinderEngine.gltf").to_str().unwrap(),
    ]);
    assert_eq!(
        (engine["nodes"].as_u64(), engine["meshes"].as_u64()),
        (Some(82), Some(29))
    );
    assert!(
        engine["instances"].as_u64().unwrap() > 29,
        "{}",
        engine["instances"]
    );
    assert!(dropped_whats(&engine).contains(&"instancing".to_string()));

    let skin = shared_model("production/simple_skin/simple_skin.gltf");
    let skin = lodstudio_json(&["info", skin.to_str().unwrap()]);
    assert_eq!(
        (skin["skins"].as_u64(), skin["animations"].as_u64()),
        (Some(1), Some(1))
    );
    for what in [
        "skin",
        "animation",
        "attribute JOINTS_0",
        "attribute WEIGHTS_0",
    ] {
        assert!(
            dropped_whats(&skin).contains(&what.to_string()),
            "{what}: {}",
            skin["dropped"]
        );
    }

    let cube = shared_model("production/AnimatedMorphCube/AnimatedMorphCube.gltf");
    let cube = lodstudio_json(&["info", cube.to_str().unwrap()]);
    assert_eq!(cube["morph_targets"].as_u64(), Some(2));
    assert!(dropped_whats(&cube).contains(&"morph targets".to_string()));

    let coat = shared_model("production/ClearCoat/ClearCoatTest.gltf");
    let coat = lodstudio_json(&["info", coat.to_str().unwrap()]);
    assert_eq!(coat["extensions"], json!(["KHR_materials_clearcoat"]));
    let clearcoat: Vec<&Value> = (coat["dropped"].as_array().unwrap().iter())
        .filter(|d| d["what"] == "KHR_materials_clearcoat")
        .collect();
    assert!(!clearcoat.is_empty());
    assert!(
        clearcoat
            .iter()
            .all(|d| d["where"].as_str().unwrap().starts_with("material "))
    );

    let torus = lodstudio_json(&["info", "builtin:torus"]);
    assert_eq!(
        (torus["nodes"].as_u64(), torus["instances"].as_u64()),
        (Some(1), Some(1))
    );
    assert_eq!(torus["dropped"], json!([]));
}

/// An export carries the scene's materials as read, their extensions
/// included (KHR_texture_transform), and lists what it cannot carry: an
/// optional extension on a primitive, whose primitives the LODs replace.
#[test]
fn an_export_carries_material_extensions_and_lists_what_it_leaves_out() {
    let tmp = tempfile::tempdir().unwrap();
    let input = shared_model("production/textureTransform/TextureTransformTest.gltf");
    let out = tmp.path().join("tt.glb");
    let args = [
        "export",
        input.to_str().unwrap(),
        "--lods",
        "source,simplify:2%",
        "-o",
        out.to_str().unwrap(),
        "--json",
    ];
    let run = lodstudio(&args);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let j: Value = serde_json::from_slice(&run.stdout).unwrap();
    assert!(!dropped_whats(&j).contains(&"KHR_texture_transform".to_string()));
    let original: Value = serde_json::from_slice(&std::fs::read(&input).unwrap()).unwrap();
    let glb = std::fs::read(&out).unwrap();
    let (json, _) = lodstudio_core::io::gltf::split_glb(&glb, "x.bin").unwrap();
    let doc: Value = serde_json::from_slice(&json).unwrap();
    assert_eq!(doc["materials"], original["materials"]);
    assert!(
        doc["materials"]
            .to_string()
            .contains("KHR_texture_transform")
    );

    // An extension nobody knows, optional, on a primitive: carried on
    // without it, listed where it was.
    let made_up = triangle_gltf(
        tmp.path(),
        "made-up.gltf",
        json!({"extensionsUsed": ["EXT_made_up"],
               "meshes": [{"primitives": [{"attributes": {"POSITION": 0},
                                           "extensions": {"EXT_made_up": {}}}]}]}),
    );
    let out = tmp.path().join("made-up.glb");
    let run = lodstudio(&[
        "export",
        &made_up,
        "--lods",
        "source",
        "-o",
        out.to_str().unwrap(),
        "--json",
    ]);
    assert!(run.status.success());
    assert!(out.is_file());
    let j: Value = serde_json::from_slice(&run.stdout).unwrap();
    let listed = &j["dropped"][0];
    assert_eq!(
        (listed["what"].as_str(), listed["where"].as_str()),
        (Some("EXT_made_up"), Some("mesh 0 primitive 0"))
    );
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(stderr.contains("not carried: EXT_made_up"), "{stderr}");
}

/// A required extension lodstudio cannot read refuses the file with exit 2,
/// naming it (a Draco-compressed file said nothing of Draco before).
#[test]
fn a_required_extension_is_refused_by_name() {
    let tmp = tempfile::tempdir().unwrap();
    for (ext, word) in [
        ("KHR_draco_mesh_compression", "Draco"),
        ("EXT_made_up", "cannot carry"),
    ] {
        let file = triangle_gltf(
            tmp.path(),
            &format!("{ext}.gltf"),
            json!({"extensionsUsed": [ext], "extensionsRequired": [ext]}),
        );
        let out = tmp.path().join("never.ply").display().to_string();
        for args in [
            vec!["info", &file],
            vec!["simplify", &file, "--ratio", "0.5", "-o", &out],
        ] {
            let run = lodstudio(&args);
            assert_eq!(run.status.code(), Some(2), "{args:?}");
            let stderr = String::from_utf8_lossy(&run.stderr);
            assert!(
                stderr.contains(ext) && stderr.contains(word),
                "{args:?}: {stderr}"
            );
            assert!(!Path::new(&out).exists());
        }
    }
}

/// `glb` (one primitive, as `gltf_writer::write_glb` writes it) stored the
/// way gltfpack `-c` stores it: every view compressed by meshoptimizer's
/// codecs into buffer 0, decoded places in a fallback buffer 1 with no
/// bytes, normals octahedral-filtered to 8 bits (KHR_mesh_quantization).
/// `tamper` edits each view's extension object before it is written.
fn meshopt_compressed(glb: &[u8], tamper: &dyn Fn(&mut Value)) -> Vec<u8> {
    use lodstudio_core::io::{gltf, gltf_writer};
    let (json, bin) = gltf::split_glb(glb, "x.bin").unwrap();
    let mut doc: Value = serde_json::from_slice(&json).unwrap();
    let prim = doc["meshes"][0]["primitives"][0].clone();
    let at = |v: &Value| v.as_u64().unwrap() as usize;
    let (normal, index) = (at(&prim["attributes"]["NORMAL"]), at(&prim["indices"]));
    let vertices = doc["accessors"][at(&prim["attributes"]["POSITION"])]["count"]
        .as_u64()
        .unwrap() as usize;
    let mut accessors: Vec<usize> = prim["attributes"]
        .as_object()
        .unwrap()
        .values()
        .map(at)
        .collect();
    accessors.push(index);
    let (mut packed, mut fallback, mut views) = (Vec::<u8>::new(), 0usize, Vec::new());
    for a in accessors {
        let acc = doc["accessors"][a].clone();
        let view = &doc["bufferViews"][at(&acc["bufferView"])];
        let start = view["byteOffset"].as_u64().unwrap_or(0) as usize
            + acc["byteOffset"].as_u64().unwrap_or(0) as usize;
        let count = at(&acc["count"]);
        let word = |i: usize| bin[start + 4 * i..start + 4 * i + 4].try_into().unwrap();
        let floats = |w: usize| -> Vec<f32> {
            (0..count * w)
                .map(|i| f32::from_le_bytes(word(i)))
                .collect()
        };
        let (stride, mode, filter, encoded) = if a == index {
            assert_eq!(acc["componentType"], 5125, "u32 indices");
            let ix: Vec<u32> = (0..count).map(|i| u32::from_le_bytes(word(i))).collect();
            (
                4,
                "TRIANGLES",
                "NONE",
                meshopt::encode_index_buffer(&ix, vertices).unwrap(),
            )
        } else if a == normal {
            let n: Vec<[f32; 4]> = floats(3)
                .chunks(3)
                .map(|c| [c[0], c[1], c[2], 0.0])
                .collect();
            let oct: Vec<[i8; 4]> = meshopt::encode_filter_oct(&n, 8);
            doc["accessors"][a]["componentType"] = json!(5120);
            doc["accessors"][a]["normalized"] = json!(true);
            (
                4,
                "ATTRIBUTES",
                "OCTAHEDRAL",
                meshopt::encode_vertex_buffer(&oct).unwrap(),
            )
        } else {
            let encoded = match acc["type"].as_str().unwrap() {
                "VEC3" => meshopt::encode_vertex_buffer(
                    &floats(3)
                        .chunks(3)
                        .map(|c| [c[0], c[1], c[2]])
                        .collect::<Vec<_>>(),
                ),
                _ => meshopt::encode_vertex_buffer(
                    &floats(2)
                        .chunks(2)
                        .map(|c| [c[0], c[1]])
                        .collect::<Vec<_>>(),
                ),
            };
            let width = if acc["type"] == "VEC3" { 12 } else { 8 };
            (width, "ATTRIBUTES", "NONE", encoded.unwrap())
        };
        while packed.len() % 4 != 0 {
            packed.push(0);
        }
        let mut ext = json!({"buffer": 0, "byteOffset": packed.len(), "byteLength": encoded.len(),
            "byteStride": stride, "count": count, "mode": mode, "filter": filter});
        tamper(&mut ext);
        packed.extend(&encoded);
        let mut v = json!({"buffer": 1, "byteOffset": fallback, "byteLength": stride * count,
            "extensions": {"EXT_meshopt_compression": ext}});
        if mode == "ATTRIBUTES" {
            v["byteStride"] = json!(stride);
        }
        fallback += (stride * count).next_multiple_of(4);
        views.push(v);
        doc["accessors"][a]["bufferView"] = json!(views.len() - 1);
        doc["accessors"][a]
            .as_object_mut()
            .unwrap()
            .remove("byteOffset");
    }
    doc["bufferViews"] = json!(views);
    while packed.len() % 4 != 0 {
        packed.push(0);
    }
    doc["buffers"] = json!([{"byteLength": packed.len()},
        {"byteLength": fallback, "extensions": {"EXT_meshopt_compression": {"fallback": true}}}]);
    let used = json!(["EXT_meshopt_compression", "KHR_mesh_quantization"]);
    doc["extensionsUsed"] = used.clone();
    doc["extensionsRequired"] = used;
    gltf_writer::glb(&doc, packed)
}

/// A meshopt-compressed file (EXT_meshopt_compression, as gltfpack writes
/// it) reads as the plain one: the same positions to the bit, the same
/// triangles, normals within their 8-bit octahedral quantization; it
/// exports the same LODs, written plain; a compressed view the format does
/// not allow, or bytes that do not decode, are refused with exit 2.
#[test]
fn meshopt_compressed_inputs_are_decoded() {
    use lodstudio_core::io::{gltf, gltf_writer};
    let tmp = tempfile::tempdir().unwrap();
    let torus = lodstudio_core::builtins::torus(1.0, 0.35, 48, 24);
    let plain = gltf_writer::write_glb(&torus);
    let compressed = meshopt_compressed(&plain, &|_| {});
    assert!(
        compressed.len() < plain.len(),
        "{} bytes from {}",
        compressed.len(),
        plain.len()
    );
    let (a, _) = gltf::read(&plain, None).unwrap();
    let (b, report) = gltf::read(&compressed, None).unwrap();
    assert_eq!(a.positions, b.positions);
    assert_eq!(a.triangles, b.triangles);
    for (n, m) in a
        .normals
        .as_ref()
        .unwrap()
        .iter()
        .zip(b.normals.as_ref().unwrap())
    {
        assert!(n.distance(*m) < 0.02, "{n} / {m}");
    }
    assert!(
        report
            .extensions
            .contains(&"EXT_meshopt_compression".to_string())
    );

    let write = |name: &str, bytes: &[u8]| {
        let path = tmp.path().join(name);
        std::fs::write(&path, bytes).unwrap();
        path.display().to_string()
    };
    let (p, c) = (write("plain.glb", &plain), write("packed.glb", &compressed));
    let export = |input: &str, out: &str| {
        let out = tmp.path().join(out).display().to_string();
        let j = lodstudio_json(&["export", input, "--lods", "source,simplify:1%", "-o", &out]);
        (j, out)
    };
    let ((jp, _), (jc, out)) = (export(&p, "p.glb"), export(&c, "c.glb"));
    for k in 0..2 {
        assert_eq!(
            jp["lods"][k]["triangles"], jc["lods"][k]["triangles"],
            "LOD {k}"
        );
    }
    let written = std::fs::read(&out).unwrap();
    let (json, _) = gltf::split_glb(&written, "x.bin").unwrap();
    let doc: Value = serde_json::from_slice(&json).unwrap();
    assert!(!String::from_utf8_lossy(&json).contains("meshopt"), "{doc}");
    assert!(doc["buffers"].as_array().unwrap().len() == 1);
    let (reread, _) = gltf::read(&written, None).unwrap();
    assert_eq!(reread.positions.len(), b.positions.len());

    // Hostile: a stride the vertex codec asserts against, a filter on
    // indices, and compressed bytes cut short.
    type Tamper<'a> = (&'a str, &'a dyn Fn(&mut Value));
    let bad: [Tamper; 3] = [
        ("stride", &|e| e["byteStride"] = json!(6)),
        ("filter", &|e| {
            if e["mode"] == "TRIANGLES" {
                e["filter"] = json!("OCTAHEDRAL")
            }
        }),
        ("short", &|e| {
            e["byteLength"] = json!(e["byteLength"].as_u64().unwrap() / 2)
        }),
    ];
    for (what, tamper) in bad {
        let file = write(&format!("{what}.glb"), &meshopt_compressed(&plain, tamper));
        let run = lodstudio(&["info", &file]);
        let stderr = String::from_utf8_lossy(&run.stderr);
        assert_eq!(run.status.code(), Some(2), "{what}: {stderr}");
        assert!(
            stderr.contains("EXT_meshopt_compression"),
            "{what}: {stderr}"
        );
    }
}
