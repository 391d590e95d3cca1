//! `triwild features`: the feature preprocessing only, written as JSON (and
//! an SVG preview).

use super::args::ParamArgs;
use crate::cli::console::{errln, outln};
use crate::exit_code;
use clap::Args;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use triwild::Error;
use triwild::FeatureAnalysis;

/// `triwild features` arguments.
#[derive(Args, Debug, Clone)]
pub(crate) struct FeaturesArgs {
    /// Input SVG file.
    input: PathBuf,
    /// Output JSON file [default: the input's path with extension .features.json].
    #[arg(short, long, value_name = "OUT.json")]
    output: Option<PathBuf>,
    /// Also write an SVG picture: primary red, secondary green, points black, input grey.
    #[arg(long, value_name = "OUT.svg")]
    preview: Option<PathBuf>,
    /// Print counts and the preprocessing time as one JSON object on stdout.
    #[arg(long)]
    stats: bool,
    #[command(flatten)]
    params: ParamArgs,
}

/// Load, preprocess, write the JSON (and preview); exit 0, or 2, 3, 4 by the
/// error's kind.
pub(crate) fn run(args: &FeaturesArgs, quiet: bool) -> ExitCode {
    let input = &args.input;
    let params = args.params.to_params();
    let fail = |path: &Path, err: Error| {
        errln!("error: {}: {err}", path.display());
        exit_code(err.kind())
    };
    // validates the parameters before anything is read
    let opts = match triwild::LoadOptions::from_params(&params) {
        Ok(o) => o,
        Err(e) => return fail(input, e),
    };
    let drawing = match triwild::load_file(input, &opts) {
        Ok(d) => d,
        Err(e) => return fail(input, e),
    };
    if !quiet {
        for w in &drawing.warnings {
            errln!("warning: {}: {w}", input.display());
        }
    }
    let analysis = match FeatureAnalysis::new(&drawing, &params) {
        Ok(a) => a,
        Err(e) => return fail(input, e),
    };
    let output = args
        .output
        .clone()
        .unwrap_or_else(|| input.with_extension("features.json"));
    let json = analysis.json().to_string();
    if let Err(e) = triwild::write_file(&output, json.as_bytes()) {
        return fail(&output, e);
    }
    if let Some(p) = &args.preview {
        if let Err(e) = triwild::write_file(p, analysis.svg(&drawing).as_bytes()) {
            return fail(p, e);
        }
    }
    if args.stats {
        let stats = serde_json::json!({"input": input, "counts": analysis.counts(), "timing_ms": analysis.timing()});
        outln!("{stats}");
    }
    ExitCode::SUCCESS
}
