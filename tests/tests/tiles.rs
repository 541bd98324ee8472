//! `lodstudio tiles` (issue 47): a 3D Tiles 1.1 tileset whose every
//! geometricError holds against an independent dense measurement of the
//! tile against the original triangles below it, whose cuts are crack-free,
//! and whose bytes do not depend on the thread count, the shard count, a
//! kill in the middle or the levels being run one at a time (item 3), nor
//! on the input being streamed and partitioned out of core (item 2).

use std::collections::{BTreeMap, HashMap};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use lodstudio_core::TriMesh;
use lodstudio_core::distance::{SamplingOptions, hausdorff_mesh_mesh};
use lodstudio_core::geom::repair::repair_mesh;
use lodstudio_core::geom::{RepairOptions, Weld};
use lodstudio_tests::{load_mesh, lodstudio, lodstudio_bin, lodstudio_json, shared_model};
use serde_json::Value;

/// Every tile of `tileset.json`, depth first: (tile, its children's indices).
fn flatten(tile: &Value, out: &mut Vec<(Value, Vec<usize>)>) -> usize {
    let me = out.len();
    out.push((tile.clone(), Vec::new()));
    let kids: Vec<usize> = tile["children"]
        .as_array()
        .map(|c| c.iter().map(|k| flatten(k, out)).collect())
        .unwrap_or_default();
    out[me].1 = kids;
    me
}

/// The original triangles below tile `i`: its leaves' contents.
fn leaves_below(tiles: &[(Value, Vec<usize>)], meshes: &[TriMesh], i: usize) -> Vec<TriMesh> {
    if tiles[i].1.is_empty() {
        return vec![meshes[i].clone()];
    }
    tiles[i]
        .1
        .iter()
        .flat_map(|k| leaves_below(tiles, meshes, *k))
        .collect()
}

/// Edges used by one triangle only, after welding equal positions.
fn border_edges(pieces: &[TriMesh]) -> usize {
    let (mesh, _) = repair_mesh(
        TriMesh::concat(pieces),
        &RepairOptions { weld: Weld::Exact },
    );
    let mut uses: HashMap<(u32, u32), u32> = HashMap::new();
    for t in &mesh.triangles {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            *uses.entry((a.min(b), a.max(b))).or_default() += 1;
        }
    }
    uses.values().filter(|u| **u == 1).count()
}

fn tiles(out: &Path, threads: &str) -> Value {
    lodstudio_json(&[
        "tiles",
        shared_model("bones.off").to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--tile-triangles",
        "512",
        "--threads",
        threads,
    ])
}

#[test]
fn every_tile_is_within_its_geometric_error_and_every_cut_is_closed() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("bones");
    let report = tiles(&out, "2");
    let original = load_mesh(&shared_model("bones.off"));
    let doc: Value =
        serde_json::from_slice(&std::fs::read(out.join("tileset.json")).unwrap()).unwrap();
    assert_eq!(doc["asset"]["version"], "1.1");
    assert_eq!(doc["root"]["refine"], "REPLACE");
    let mut all = Vec::new();
    flatten(&doc["root"], &mut all);
    assert_eq!(report["tiles"].as_u64(), Some(all.len() as u64));
    assert!(report["levels"].as_u64().unwrap() >= 4, "{report}");
    let meshes: Vec<TriMesh> = all
        .iter()
        .map(|(t, _)| load_mesh(&out.join(t["content"]["uri"].as_str().unwrap())))
        .collect();
    // Leaves: the original triangles, each once.
    let leaves: usize = all
        .iter()
        .zip(&meshes)
        .filter(|((_, kids), _)| kids.is_empty())
        .map(|(_, m)| m.triangles.len())
        .sum();
    assert_eq!(leaves, original.triangles.len());
    let sampling = SamplingOptions {
        samples: 20_000,
        seed: 9,
    };
    for (i, (tile, kids)) in all.iter().enumerate() {
        let error = tile["geometricError"].as_f64().unwrap() as f32;
        let b: Vec<f64> = serde_json::from_value(tile["boundingVolume"]["box"].clone()).unwrap();
        assert_eq!(b.len(), 12);
        // The box (z-up) holds the content (y-up, turned z-up).
        for p in &meshes[i].positions {
            let z_up = [p.x as f64, -p.z as f64, p.y as f64];
            for (axis, (c, h)) in [(b[0], b[3]), (b[1], b[7]), (b[2], b[11])]
                .iter()
                .enumerate()
            {
                assert!((z_up[axis] - c).abs() <= h.abs() * (1.0 + 1e-5) + 1e-6);
            }
        }
        if kids.is_empty() {
            assert_eq!(error, 0.0, "a leaf is the original");
            continue;
        }
        for k in kids {
            assert!(all[*k].0["geometricError"].as_f64().unwrap() as f32 <= error);
        }
        let below = TriMesh::concat(&leaves_below(&all, &meshes, i));
        let measured = hausdorff_mesh_mesh(&below, &meshes[i], &sampling).two_sided();
        assert!(measured <= error, "tile {i}: measured {measured} > {error}");
        assert!(measured > 0.0 && meshes[i].triangles.len() < below.triangles.len());
    }
    assert_eq!(
        report["root_geometric_error"].as_f64(),
        all[0].0["geometricError"].as_f64()
    );
    // Cuts mixing levels are closed, as the original is: the root's first
    // child refined to its leaves beside its second child whole, and every
    // level whole.
    assert_eq!(border_edges(std::slice::from_ref(&original)), 0);
    let [first, second] = [all[0].1[0], all[0].1[1]];
    let mut cut = leaves_below(&all, &meshes, first);
    cut.push(meshes[second].clone());
    assert_eq!(border_edges(&cut), 0, "a mixed cut");
    let mut level = vec![0usize];
    while !level.is_empty() {
        let cut: Vec<TriMesh> = level.iter().map(|i| meshes[*i].clone()).collect();
        assert_eq!(border_edges(&cut), 0, "level {level:?}");
        level = level.iter().flat_map(|i| all[*i].1.clone()).collect();
    }
    // One thread writes the same bytes; an existing tileset needs --force.
    let one = tmp.path().join("one");
    tiles(&one, "1");
    for (tile, _) in &all {
        let uri = tile["content"]["uri"].as_str().unwrap();
        assert_eq!(
            std::fs::read(one.join(uri)).unwrap(),
            std::fs::read(out.join(uri)).unwrap()
        );
    }
    assert_eq!(
        std::fs::read(one.join("tileset.json")).unwrap(),
        std::fs::read(out.join("tileset.json")).unwrap()
    );
    let again = lodstudio(&["tiles", "builtin:torus", "-o", one.to_str().unwrap()]);
    assert_eq!(again.status.code(), Some(2));
    // A folder whose tiles/ lodstudio did not make: refused, and with
    // --force its own files are left where they are.
    let foreign = tmp.path().join("foreign");
    std::fs::create_dir_all(foreign.join("tiles")).unwrap();
    std::fs::write(foreign.join("tiles/car.glb"), b"the user's").unwrap();
    let args = ["tiles", "builtin:torus", "-o", foreign.to_str().unwrap()];
    assert_eq!(lodstudio(&args).status.code(), Some(2));
    let forced = lodstudio(&[&args[..], &["--force"]].concat());
    assert!(
        forced.status.success(),
        "{}",
        String::from_utf8_lossy(&forced.stderr)
    );
    assert_eq!(
        std::fs::read(foreign.join("tiles/car.glb")).unwrap(),
        b"the user's"
    );
    let bad = lodstudio(&[
        "tiles",
        "builtin:torus",
        "-o",
        tmp.path().join("x").to_str().unwrap(),
        "--tile-triangles",
        "0",
    ]);
    assert_eq!(bad.status.code(), Some(2));
    assert!(
        !tmp.path().join("x").exists(),
        "nothing written for a bad budget"
    );
}

/// The truck's tiles wear its materials and textures, at every level.
#[test]
fn tiles_carry_materials_and_textures() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("truck");
    let report = lodstudio_json(&[
        "tiles",
        shared_model("CesiumMilkTruck.glb").to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--tile-triangles",
        "1024",
    ]);
    let tiles = report["tiles"].as_u64().unwrap();
    assert!(tiles >= 7, "{report}");
    for i in 0..tiles {
        let info = lodstudio_json(&["info", out.join(format!("tiles/{i}.glb")).to_str().unwrap()]);
        assert!(
            info["textured_materials"].as_u64().unwrap() >= 1,
            "tile {i}: {info}"
        );
    }
}

/// `lodstudio tiles` on the bunny at 4,096 triangles a leaf into `out`.
fn bunny(out: &Path) -> Command {
    let mut c = Command::new(lodstudio_bin());
    c.args([
        "tiles",
        shared_model("stanford-bunny.obj").to_str().unwrap(),
    ])
    .args([
        "-o",
        out.to_str().unwrap(),
        "--tile-triangles",
        "4096",
        "--json",
    ])
    .env_remove("DISPLAY")
    .env_remove("WAYLAND_DISPLAY");
    c
}

fn report(c: &mut Command) -> Value {
    let out = c.output().unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap()
}

/// Every file under `dir` (relative path, bytes), the work folder left out
/// unless `work`.
fn files(dir: &Path, work: bool) -> BTreeMap<PathBuf, Vec<u8>> {
    fn walk(root: &Path, at: &Path, work: bool, out: &mut BTreeMap<PathBuf, Vec<u8>>) {
        for e in std::fs::read_dir(at).unwrap().map(Result::unwrap) {
            let path = e.path();
            if path.is_dir() {
                if work || e.file_name() != ".lodstudio-tiles" {
                    walk(root, &path, work, out);
                }
            } else {
                let bytes = std::fs::read(&path).unwrap();
                out.insert(path.strip_prefix(root).unwrap().to_path_buf(), bytes);
            }
        }
    }
    let mut out = BTreeMap::new();
    walk(dir, dir, work, &mut out);
    out
}

/// Item 3: three shards started at once write what one run writes; a run
/// killed between tiles leaves whole files and the next goes on from
/// them, to the same bytes; levels run one at a time (a job per level)
/// in any shard order give them too.
#[test]
fn shards_at_once_a_killed_run_and_single_levels_write_one_runs_bytes() {
    let tmp = tempfile::tempdir().unwrap();
    let one = tmp.path().join("one");
    let whole = report(bunny(&one).args(["--threads", "2"]));
    let tiles = whole["tiles"].as_u64().unwrap() as usize;
    assert!(tiles >= 31 && whole["built"] == tiles, "{whole}");
    let reference = files(&one, false);
    assert_eq!(
        reference.len(),
        tiles + 1,
        "tileset.json and a GLB per tile"
    );

    let three = tmp.path().join("three");
    let shards: Vec<_> = (0..3)
        .map(|i| {
            bunny(&three)
                .args(["--shard", &format!("{i}/3"), "--threads", "1"])
                .stdout(Stdio::piped())
                .stderr(Stdio::piped())
                .spawn()
                .unwrap()
        })
        .collect();
    let mut built = 0;
    for child in shards {
        let out = child.wait_with_output().unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let r: Value = serde_json::from_slice(&out.stdout).unwrap();
        assert_eq!(r["root_geometric_error"], whole["root_geometric_error"]);
        built += r["built"].as_u64().unwrap() as usize;
    }
    assert_eq!(built, tiles, "every tile made once over the shards");
    assert_eq!(
        files(&three, false),
        reference,
        "three shards, one run's bytes"
    );

    // Killed once its first parent is made (leaves are made by planning).
    let killed = tmp.path().join("killed");
    let mut child = bunny(&killed)
        .args(["--threads", "1"])
        .stdout(Stdio::null())
        .spawn()
        .unwrap();
    let work = killed.join(".lodstudio-tiles");
    let start = std::time::Instant::now();
    // Records written whole: a `.N.json.part` being written is not one.
    let made = || {
        std::fs::read_dir(work.join("made")).map_or(0, |d| {
            d.flatten()
                .filter(|e| !e.file_name().to_string_lossy().starts_with('.'))
                .count()
        })
    };
    let leaves = || -> Option<usize> {
        let plan: Value =
            serde_json::from_slice(&std::fs::read(work.join("plan.json")).ok()?).ok()?;
        Some(
            plan["children"]
                .as_array()?
                .iter()
                .filter(|k| k.as_array().is_some_and(|k| k.is_empty()))
                .count(),
        )
    };
    while leaves().is_none_or(|l| made() <= l) && start.elapsed().as_secs() < 120 {
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    child.kill().unwrap();
    let _ = child.wait();
    let before = made();
    assert!(
        before < tiles,
        "killed before the end: {before} of {tiles} made"
    );
    assert!(!killed.join("tileset.json").exists());
    let resumed = report(&mut bunny(&killed));
    assert!(
        resumed["reused"].as_u64().unwrap() as usize >= before,
        "{resumed}"
    );
    assert_eq!(
        resumed["built"].as_u64().unwrap() as usize + before,
        tiles,
        "only what was not made: {resumed}"
    );
    assert_eq!(files(&killed, false), reference, "resumed, one run's bytes");
    let strays: Vec<_> = files(&killed, true)
        .into_keys()
        .filter(|p| p.to_string_lossy().ends_with(".part"))
        .collect();
    assert!(strays.is_empty(), "{strays:?}");
    // The same command again is no overwrite: it finds everything made.
    let again = report(&mut bunny(&killed));
    assert_eq!(again["built"], 0);

    // One level at a time, deepest first, as Kubernetes jobs per level
    // run them; the root's level before its children's is refused.
    let levels = whole["levels"].as_u64().unwrap() as usize;
    let by_level = tmp.path().join("levels");
    let early = bunny(&by_level).args(["--level", "0"]).output().unwrap();
    assert_eq!(
        early.status.code(),
        Some(2),
        "{}",
        String::from_utf8_lossy(&early.stderr)
    );
    assert!(String::from_utf8_lossy(&early.stderr).contains("needs level 1 first"));
    let past = bunny(&by_level)
        .args(["--level", &levels.to_string()])
        .output()
        .unwrap();
    assert_eq!(past.status.code(), Some(2));
    for level in (0..levels).rev() {
        for index in ["1", "0"] {
            let r = report(
                bunny(&by_level)
                    .args(["--level", &level.to_string(), "--shards", "2"])
                    .env("JOB_COMPLETION_INDEX", index),
            );
            assert_eq!(r["output"].is_null(), level > 0, "{r}");
        }
    }
    assert_eq!(
        files(&by_level, false),
        reference,
        "level by level, one run's bytes"
    );
}

/// The shipped Kubernetes manifest's command line, as written (the scan and
/// the shared volume swapped for bones and a scratch folder, with small
/// tiles), run as every
/// index of the job one after another: the first makes everything, the
/// others find it made, and the tileset is one plain run's.
#[test]
fn the_kubernetes_manifest_runs_as_written() {
    let manifest = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../deploy/kubernetes/tiles-job.yaml"),
    )
    .unwrap();
    let lines: Vec<&str> = manifest.lines().map(str::trim).collect();
    let first = lines.iter().position(|l| *l == "args:").unwrap() + 1;
    let args: Vec<String> = lines[first..]
        .iter()
        .filter(|l| !l.starts_with('#'))
        .map_while(|l| l.strip_prefix("- "))
        .map(|a| a.trim_matches('"').to_string())
        .collect();
    let completions: usize = lines
        .iter()
        .find_map(|l| l.strip_prefix("completions: "))
        .unwrap()
        .parse()
        .unwrap();
    let shards = args.iter().position(|a| a == "--shards").unwrap() + 1;
    assert_eq!(
        args[shards],
        completions.to_string(),
        "completions = --shards"
    );
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("scan");
    let bones = shared_model("bones.off");
    // Small tiles, so that bones has levels to share.
    let swapped: Vec<&str> = args
        .iter()
        .map(|a| match a.as_str() {
            "/assets/scan.ply" => bones.to_str().unwrap(),
            "/assets/tiles/scan" => out.to_str().unwrap(),
            a => a,
        })
        .chain(["--tile-triangles", "512"])
        .collect();
    let mut built = 0;
    for index in 0..completions {
        let run = Command::new(lodstudio_bin())
            .args(&swapped)
            .env("JOB_COMPLETION_INDEX", index.to_string())
            .output()
            .unwrap();
        assert!(
            run.status.success(),
            "{}",
            String::from_utf8_lossy(&run.stderr)
        );
        let r: Value = serde_json::from_slice(&run.stdout).unwrap();
        built += r["built"].as_u64().unwrap();
    }
    let plain = tmp.path().join("plain");
    let r = lodstudio_json(&[
        "tiles",
        bones.to_str().unwrap(),
        "-o",
        plain.to_str().unwrap(),
        "--tile-triangles",
        "512",
    ]);
    assert!(r["tiles"].as_u64() >= Some(31), "{r}");
    assert_eq!(Some(built), r["tiles"].as_u64(), "each tile made once");
    assert_eq!(files(&out, false), files(&plain, false));
}

/// Item 2: a PLY larger than `--memory` is streamed and partitioned out of
/// core (its cells split on disk), and the tileset is the in-memory one,
/// byte for byte: the horse as it is (binary, with normals) and as gzipped
/// ascii; a truncated one is refused and leaves nothing; another format
/// over the memory asked for is refused, not read.
#[test]
fn out_of_core_tiles_are_the_in_memory_tiles() {
    use std::io::Write as _;
    let tmp = tempfile::tempdir().unwrap();
    let horse = shared_model("horse.ply");
    let ascii_gz = tmp.path().join("horse-ascii.ply.gz");
    let mesh = load_mesh(&horse);
    let text = lodstudio_core::io::ply::write_mesh(&mesh, lodstudio_core::io::ply::Encoding::Ascii);
    let mut gz = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
    gz.write_all(&text).unwrap();
    std::fs::write(&ascii_gz, gz.finish().unwrap()).unwrap();
    for (name, input) in [("binary", &horse), ("ascii-gz", &ascii_gz)] {
        let run = |dir: &str, memory: Option<&str>| {
            let out = tmp.path().join(format!("{name}-{dir}"));
            let mut args = vec![
                "tiles",
                input.to_str().unwrap(),
                "-o",
                out.to_str().unwrap(),
                "--tile-triangles",
                "2048",
            ];
            args.extend(memory.map(|m| ["--memory", m]).into_iter().flatten());
            (lodstudio_json(&args), out)
        };
        let (memory, in_memory) = run("memory", None);
        let (streamed, out_of_core) = run("streamed", Some("1M"));
        assert_eq!(memory["out_of_core"], false, "{memory}");
        assert_eq!(streamed["out_of_core"], true, "{streamed}");
        assert!(streamed["tiles"].as_u64() >= Some(63), "{streamed}");
        assert_eq!(memory["input_triangles"], streamed["input_triangles"]);
        assert_eq!(
            files(&in_memory, false),
            files(&out_of_core, false),
            "{name}"
        );
        let spill = out_of_core.join(".lodstudio-tiles/spill");
        assert_eq!(
            std::fs::read_dir(spill).unwrap().count(),
            0,
            "spill emptied"
        );
    }
    // Cut short: refused (exit 2), and the folder it would have made is gone.
    let bytes = std::fs::read(&horse).unwrap();
    let cut = tmp.path().join("cut.ply");
    std::fs::write(&cut, &bytes[..bytes.len() * 2 / 3]).unwrap();
    let out = tmp.path().join("cut");
    let run = lodstudio(&[
        "tiles",
        cut.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--memory",
        "1M",
    ]);
    assert_eq!(
        run.status.code(),
        Some(2),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    assert!(!out.exists());
    let off = lodstudio(&[
        "tiles",
        shared_model("bones.off").to_str().unwrap(),
        "-o",
        tmp.path().join("off").to_str().unwrap(),
        "--memory",
        "10K",
    ]);
    assert_eq!(off.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&off.stderr).contains("out of core reads PLY"));
}
