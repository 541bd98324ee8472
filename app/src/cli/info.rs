//! `info`: counts, topology and the repairs made on load.

use super::*;

#[derive(Args, Debug)]
pub struct InfoArgs {
    /// A model file, or builtin:NAME.
    #[arg(required_unless_present = "builtins")]
    file: Option<PathBuf>,
    /// List the built-in models.
    #[arg(long)]
    builtins: bool,
    /// Print one JSON object.
    #[arg(long)]
    json: bool,
    #[command(flatten)]
    input: InputArgs,
}

pub fn run(args: InfoArgs) -> Result<(), CliError> {
    if args.builtins {
        if args.json {
            let list: Vec<_> = builtins::NAMES
                .iter()
                .map(|(n, d)| serde_json::json!({"name": format!("builtin:{n}"), "description": d}))
                .collect();
            println!("{}", serde_json::json!({ "builtins": list }));
        } else {
            for (n, d) in builtins::NAMES {
                println!("builtin:{n:<20} {d}");
            }
        }
        return Ok(());
    }
    let file = args.file.expect("clap requires FILE without --builtins");
    if let Ok(bytes) = io::read_file(&file, &Progress::new())
        && io::hierarchy_file::is_hierarchy(&bytes)
    {
        // A saved hierarchy: what it holds, checked whole (decoded and its
        // invariants verified, as a cut would reopen it).
        let (h, _) = lodstudio_core::open::reopen(&bytes)
            .map_err(|e| CliError::BadInput(format!("{}: {e}", file.display())))?;
        let j = serde_json::json!({
            "file": file.display().to_string(),
            "kind": "hierarchy",
            "method": h.method,
            "version": h.version,
            "params": h.params,
            "bytes": bytes.len(),
        });
        if args.json {
            println!("{j}");
        } else {
            println!(
                "{}: saved {} hierarchy (format {}), {}",
                file.display(),
                h.method,
                h.version,
                h.params
            );
        }
        return Ok(());
    }
    let opts = args.input.load_options()?;
    let loaded = lodstudio_core::open::open(&file, &opts, &Progress::new())?;
    let summary = ModelSummary::of(&loaded);
    if args.json {
        let mut v = summary.to_json();
        v["file"] = serde_json::json!(file.display().to_string());
        println!("{v}");
    } else {
        println!("{}", file.display());
        for (label, value) in summary.lines() {
            println!("  {label:<22} {value}");
        }
        let a = &summary.asset;
        println!(
            "  {:<22} {} nodes, {} meshes, {} instances; {} skins, {} animations, {} morph targets",
            "asset", a.nodes, a.meshes, a.instances, a.skins, a.animations, a.morph_targets
        );
        if !a.extensions.is_empty() {
            println!("  {:<22} {}", "extensions", a.extensions.join(", "));
        }
        for d in &a.dropped {
            println!("  not carried: {} ({})", d.what, d.place);
        }
    }
    Ok(())
}
