//! The single-file command: `triwild IN.svg [-o OUT.msh] [--preview OUT.svg
//! [--preview-size]] [--stats]`.

use super::args::{FormatArgs, ParamArgs, RegionArgs};
use crate::cli::console::{errln, outln};
use crate::exit_code;
use clap::Args;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use triwild::{Error, MeshFormat, RunOptions};

/// The single-file command's arguments.
#[derive(Args, Debug, Clone)]
pub(crate) struct MeshArgs {
    /// Input SVG file.
    input: Option<PathBuf>,
    /// Output mesh file [default: the input's path with extension .msh, or
    /// .vtu with --format vtu].
    #[arg(short, long, value_name = "OUT.msh")]
    output: Option<PathBuf>,
    /// Mesh file format: gmsh .msh, or a VTK XML unstructured grid of Lagrange
    /// cells tagged by region and curve (for ParaView) [default: vtu when the
    /// output's name ends in .vtu, else msh].
    #[arg(long, value_enum)]
    format: Option<FormatArg>,
    /// Also write an SVG drawing of the mesh.
    #[arg(long, value_name = "OUT.svg")]
    preview: Option<PathBuf>,
    /// Fill the preview's triangles by how their size matches the size field:
    /// mean edge length over h at the centroid, blue below 4/5, neutral within
    /// [4/5, 4/3], red above 4/3 (with a legend), instead of by region colour.
    #[arg(long, requires = "preview")]
    preview_size: bool,
    /// Print one JSON object of statistics on stdout.
    #[arg(long)]
    stats: bool,
    #[command(flatten)]
    msh: FormatArgs,
    #[command(flatten)]
    params: ParamArgs,
    #[command(flatten)]
    regions: RegionArgs,
}

/// The mesh file formats of `--format`.
#[derive(clap::ValueEnum, Debug, Clone, Copy, PartialEq, Eq)]
enum FormatArg {
    /// gmsh MSH (4.1 or 2.2: --msh-version).
    Msh,
    /// VTK XML unstructured grid (.vtu).
    Vtu,
}

/// The format asked for, else the one the output's extension names (`.vtu`),
/// else .msh.
fn mesh_format(format: Option<FormatArg>, output: Option<&Path>) -> MeshFormat {
    let by_name = output
        .and_then(|p| p.extension())
        .is_some_and(|e| e.eq_ignore_ascii_case("vtu"));
    match format {
        Some(FormatArg::Vtu) => MeshFormat::Vtu,
        Some(FormatArg::Msh) => MeshFormat::Msh,
        None if by_name => MeshFormat::Vtu,
        None => MeshFormat::Msh,
    }
}

/// The default output path: the input with extension `.msh` (`.vtu`).
fn default_output(input: &Path, format: MeshFormat) -> PathBuf {
    input.with_extension(match format {
        MeshFormat::Msh => "msh",
        MeshFormat::Vtu => "vtu",
    })
}

/// Mesh one file, print its warnings (unless `quiet`) and statistics; exit 0,
/// or 2, 3, 4 by the error's kind.
pub(crate) fn run(args: &MeshArgs, quiet: bool) -> ExitCode {
    let Some(input) = &args.input else {
        errln!("error: no input file given (try `triwild --help`)");
        return ExitCode::from(2);
    };
    #[cfg(feature = "test-hooks")]
    super::hooks::trigger(input);
    let format = mesh_format(args.format, args.output.as_deref());
    let output = args
        .output
        .clone()
        .unwrap_or_else(|| default_output(input, format));
    let opts = RunOptions::new(args.params.to_params())
        .with_msh(args.msh.to_options())
        .with_format(format)
        .with_preview(args.preview.clone())
        .with_preview_size(args.preview_size)
        .with_regions(args.regions.to_options())
        .with_paint(args.regions.paint_options());
    // The library's write errors do not say which file; an unwritable preview
    // is reported here, naming the preview, before anything is meshed.
    if let Some(preview) = &args.preview {
        if let Err(err) = triwild::check_writable(preview) {
            errln!("error: {}: {err}", preview.display());
            return exit_code(err.kind());
        }
    }
    let result = triwild::run_file(input, &output, &opts);
    // The parser's own warnings: one line among the run's warnings (and in
    // --stats) on success; on failure none beside the error's one line, but
    // in it when the drawing had nothing to mesh.
    let parser = super::parser_log::folded(&super::parser_log::take());
    match result {
        Ok(mut report) => {
            report.warnings.extend(parser);
            if !quiet {
                for w in &report.warnings {
                    errln!("warning: {}: {w}", input.display());
                }
            }
            if args.stats {
                match serde_json::to_string(&report) {
                    Ok(s) => outln!("{s}"),
                    Err(e) => {
                        errln!("error: {}: cannot format statistics: {e}", input.display());
                        return ExitCode::from(4);
                    }
                }
            }
            ExitCode::SUCCESS
        }
        Err(err) => {
            let file = match &err {
                Error::Write(_) => &output,
                _ => input,
            };
            // nothing left to mesh: what the parser skipped may be why
            match (&err, parser) {
                (Error::NoGeometry(_), Some(parser)) => {
                    errln!("error: {}: {err}; {parser}", file.display());
                }
                _ => errln!("error: {}: {err}", file.display()),
            }
            exit_code(err.kind())
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_format_is_the_flag_else_the_extension() {
        let vtu = Some(Path::new("out/a.VTU"));
        assert_eq!(mesh_format(None, vtu), MeshFormat::Vtu);
        assert_eq!(mesh_format(None, Some(Path::new("a.msh"))), MeshFormat::Msh);
        assert_eq!(mesh_format(None, None), MeshFormat::Msh);
        assert_eq!(mesh_format(Some(FormatArg::Msh), vtu), MeshFormat::Msh);
        assert_eq!(mesh_format(Some(FormatArg::Vtu), None), MeshFormat::Vtu);
        let input = Path::new("d/x.svg");
        assert_eq!(default_output(input, MeshFormat::Vtu), Path::new("d/x.vtu"));
    }
}
