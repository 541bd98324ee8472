//! Hostile sizes (issue 29): a gzip bomb and headers claiming billions of
//! elements are refused within a second and in little memory, with an error
//! that names the cap that stopped them.

use std::io::{Read as _, Seek as _, Write as _};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use lodstudio_tests::lodstudio_bin;

/// What a measured run of the CLI gave.
struct Measured {
    code: i32,
    stderr: String,
    time: Duration,
    /// Peak resident memory of the child, from its own `rusage`.
    max_rss_bytes: u64,
}

/// Runs `lodstudio ARGS` (with `env`) and reaps it with `wait4`, so the peak
/// memory is this child's alone, not that of other tests' children.
#[expect(clippy::zombie_processes, reason = "reaped by wait4, for its rusage")]
fn measured(args: &[&str], env: &[(&str, &str)]) -> Measured {
    // An unnamed temporary file: nothing is left behind, however the run ends.
    let mut err = tempfile::tempfile().unwrap();
    let start = Instant::now();
    let child = Command::new(lodstudio_bin())
        .args(args)
        .envs(env.iter().copied())
        .stdout(Stdio::null())
        .stderr(err.try_clone().unwrap())
        .spawn()
        .expect("run lodstudio");
    let mut status = 0;
    // SAFETY: rusage is plain data; wait4 fills it for our own child.
    let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
    let pid = unsafe { libc::wait4(child.id() as libc::pid_t, &mut status, 0, &mut usage) };
    let time = start.elapsed();
    assert_eq!(pid, child.id() as libc::pid_t, "wait4 reaped the child");
    assert!(
        libc::WIFEXITED(status),
        "lodstudio {args:?} died of a signal"
    );
    let mut stderr = String::new();
    err.rewind().unwrap();
    err.read_to_string(&mut stderr).unwrap();
    Measured {
        code: libc::WEXITSTATUS(status),
        stderr,
        time,
        max_rss_bytes: usage.ru_maxrss as u64 * 1024, // KiB on Linux
    }
}

/// `dir/name`: `members` gzip members of 16 MiB of zeros each, after `head`
/// (its own member).
fn gzip_bomb(dir: &Path, name: &str, head: &[u8], members: usize) -> PathBuf {
    let gz = |data: &[u8]| {
        let mut e = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::best());
        e.write_all(data).unwrap();
        e.finish().unwrap()
    };
    let zeros = gz(&vec![0u8; 16 << 20]);
    let mut bytes = if head.is_empty() {
        Vec::new()
    } else {
        gz(head)
    };
    for _ in 0..members {
        bytes.extend_from_slice(&zeros);
    }
    let path = dir.join(name);
    std::fs::write(&path, bytes).unwrap();
    path
}

const MB: u64 = 1 << 20;

fn assert_refused_fast_and_small(m: &Measured, what: &str) {
    assert_eq!(m.code, 2, "{what}: {}", m.stderr);
    assert_eq!(
        m.stderr.trim().lines().count(),
        1,
        "{what}: one line: {}",
        m.stderr
    );
    assert!(!m.stderr.contains("panicked"), "{what}: {}", m.stderr);
    assert!(m.time < Duration::from_secs(1), "{what}: {:?}", m.time);
    assert!(
        m.max_rss_bytes < 100 * MB,
        "{what}: {} MB resident",
        m.max_rss_bytes / MB
    );
}

#[test]
fn a_two_gigabyte_gzip_bomb_is_refused_within_a_second_and_100_mb() {
    // 2 MB on disk, 2 GiB inflated: no model's header within its first bytes.
    let tmp = tempfile::tempdir().unwrap();
    let bomb = gzip_bomb(tmp.path(), "bomb.ply.gz", b"", 128);
    assert!(std::fs::metadata(&bomb).unwrap().len() < 4 * MB);
    let m = measured(&["info", bomb.to_str().unwrap()], &[]);
    assert_refused_fast_and_small(&m, "bomb");
    assert!(m.stderr.contains("inside the gzip stream"), "{}", m.stderr);
}

#[test]
fn a_gzip_bomb_behind_a_valid_header_stops_at_the_cap_it_names() {
    let header = b"ply\nformat binary_little_endian 1.0\nelement vertex 100000000\n\
                   property float x\nproperty float y\nproperty float z\nend_header\n";
    let tmp = tempfile::tempdir().unwrap();
    let bomb = gzip_bomb(tmp.path(), "headed.ply.gz", header, 128);
    let path = bomb.to_str().unwrap();
    let m = measured(&["info", path, "--max-decompressed", "32M"], &[]);
    assert_refused_fast_and_small(&m, "--max-decompressed 32M");
    assert!(m.stderr.contains("32.0 MiB"), "{}", m.stderr);
    assert!(m.stderr.contains("--max-decompressed"), "{}", m.stderr);

    let m = measured(&["info", path], &[("LODSTUDIO_MAX_DECOMPRESSED", "16M")]);
    assert_refused_fast_and_small(&m, "LODSTUDIO_MAX_DECOMPRESSED=16M");
    assert!(m.stderr.contains("16.0 MiB"), "{}", m.stderr);

    // Under the cap the same stream is a model (so the cap, not the data, refused it).
    let small = gzip_bomb(tmp.path(), "headed-small.ply.gz", header, 0);
    let m = measured(
        &["info", small.to_str().unwrap(), "--max-decompressed", "32M"],
        &[],
    );
    assert_eq!(m.code, 2, "a header without its vertices: {}", m.stderr);
    assert!(!m.stderr.contains("after decompression"), "{}", m.stderr);
}

#[test]
fn a_ply_header_claiming_4e9_vertices_is_refused_before_allocating() {
    let tmp = tempfile::tempdir().unwrap();
    let ply = tmp.path().join("huge.ply");
    std::fs::write(
        &ply,
        "ply\nformat ascii 1.0\nelement vertex 4000000000\nproperty float x\n\
         property float y\nproperty float z\nelement face 0\n\
         property list uchar int vertex_indices\nend_header\n",
    )
    .unwrap();
    let m = measured(&["info", ply.to_str().unwrap()], &[]);
    assert_refused_fast_and_small(&m, "4e9 vertices");
    assert!(m.stderr.contains("4000000000 vertex"), "{}", m.stderr);

    // Binary, with the bytes present for none of them: the estimate is named.
    let bin = tmp.path().join("huge-binary.ply");
    std::fs::write(
        &bin,
        "ply\nformat binary_little_endian 1.0\nelement vertex 4000000000\n\
         property float x\nproperty float y\nproperty float z\nend_header\n",
    )
    .unwrap();
    let m = measured(&["info", bin.to_str().unwrap()], &[]);
    assert_refused_fast_and_small(&m, "4e9 binary vertices");
}
