//! Nothing is dropped silently (issue 49, item 6): what a glTF asset holds
//! besides its triangles is counted by `info --json` and, where an export
//! leaves it out, listed in `dropped` and on stderr; an extension the file
//! requires and lodstudio cannot read refuses it with exit 2, by name.

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
        ("EXT_meshopt_compression", "meshopt"),
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
