//! `triwild check`: certify a gmsh mesh and print the verdict, as a summary
//! or as one JSON object.

use crate::cli::console::{errln, outln};
use clap::Args;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use triwild::FileCheck;

/// `triwild check` arguments.
#[derive(Args, Debug, Clone)]
pub(crate) struct CheckArgs {
    /// Mesh file (.msh).
    input: PathBuf,
    /// Print one JSON object instead of the summary.
    #[arg(long)]
    json: bool,
}

/// Read a mesh, certify it, print a summary or JSON; exit 0 valid, 1 invalid,
/// 2 unreadable.
pub(crate) fn run(args: &CheckArgs) -> ExitCode {
    let input = &args.input;
    let mesh = match triwild::read_msh_file(input) {
        Ok(m) => m,
        Err(e) => {
            if args.json {
                let v = serde_json::json!({"file": input, "readable": false, "valid": false, "error": e.to_string()});
                outln!("{v}");
            }
            errln!("error: {}: {e}", input.display());
            return ExitCode::from(2);
        }
    };
    let opts = triwild::CertifyOptions::DEFAULT;
    let r = triwild::check_msh(&mesh, &opts);
    if args.json {
        let mut v = serde_json::to_value(&r).unwrap_or_default();
        if let Some(o) = v.as_object_mut() {
            o.insert("file".into(), serde_json::json!(input));
            o.insert("readable".into(), true.into());
            o.insert("invalid".into(), r.mesh.invalid().into());
        }
        outln!("{v}");
    } else {
        print_summary(input, &r);
    }
    ExitCode::from(if r.valid { 0 } else { 1 })
}

/// The human-readable verdict: validity, triangle counts by order, the worst
/// Jacobian ratio and the area.
fn print_summary(input: &Path, r: &FileCheck) {
    let m = &r.mesh;
    let orders: Vec<String> = m
        .by_order
        .iter()
        .zip(1..)
        .filter(|(n, _)| **n > 0)
        .map(|(n, o)| format!("{n} of order {o}"))
        .collect();
    outln!(
        "{}: {}",
        input.display(),
        if r.valid {
            "valid".to_owned()
        } else {
            format!("INVALID ({})", r.reasons.join(", "))
        }
    );
    outln!(
        "  triangles: {} ({}), {} curved, {} invalid",
        m.triangles,
        orders.join(", "),
        m.curved,
        m.invalid()
    );
    if let Some(w) = m.worst_element {
        outln!(
            "  min Jacobian ratio: {:.6} (triangle {w})",
            m.min_detj_ratio
        );
    }
    outln!("  area: {}", m.total_area);
}
