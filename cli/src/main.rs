//! `isolab`: list algorithms and fields, extract a mesh with metrics, mesh a label map, or measure
//! a mesh file.
//!
//! Exit codes: 0 success; 1 a failed extraction (bad mesh or volume file, impossible lattice,
//! non-finite field, unwritable output); 2 a usage error (unknown algorithm, post-process or
//! field, bad arguments) or a mesh `isolab metrics` cannot read.

use clap::{Parser, Subcommand};
use isolab_algorithms::fields;
use isolab_io as io;
use isolab_io::volume::Inside;
use isolab_metrics::MeshMetrics;
use isolab_pipeline::{run, write_json, LatticeKind, Measure, OutputSpace, RunConfig, RunError, Sparse};
use std::path::PathBuf;
use std::process::ExitCode;

mod labels;

#[derive(Parser)]
#[command(name = "isolab", version, about = "Extract and compare isosurface meshes from scalar fields")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

// Parsed once per process: the size of the largest variant does not matter.
#[allow(clippy::large_enum_variant)]
#[derive(Subcommand)]
enum Command {
    /// List algorithms, post-processes and fields.
    List,
    /// Sample a field, extract a mesh, and optionally write it and its metrics.
    Extract {
        /// Algorithm name (see `isolab list`).
        #[arg(long, short)]
        algorithm: String,
        /// Built-in field name, a mesh file (.obj, .ply, .stl, .glb, .gltf: its signed distance) or
        /// a volume file (.nii, .nii.gz, .nrrd, .nhdr, .mhd, .mha, a zarr store's folder: its last axis
        /// is x, or a grid --samples-out wrote).
        #[arg(long, short)]
        field: String,
        /// Samples along the longest side of the domain (at least 2; default 64). A volume file is
        /// meshed on its own voxel grid unless this or --dims is given, which resamples it.
        #[arg(long, short)]
        resolution: Option<usize>,
        /// Exact samples per axis, NX,NY,NZ or NXxNYxNZ (overrides --resolution).
        #[arg(long, value_parser = parse_dims)]
        dims: Option<[usize; 3]>,
        /// Lattice to sample on.
        #[arg(long, value_enum, default_value_t = LatticeKind::Cubic)]
        lattice: LatticeKind,
        /// Iso-value, in the input's own values (default 0; for a scan, Otsu's threshold; for a
        /// grid --samples-out wrote, its own).
        #[arg(long, allow_negative_numbers = true)]
        iso: Option<f32>,
        /// Which side of the iso-value is inside (default: above for volume files, where the
        /// object is brighter than its background; below for distance fields).
        #[arg(long, value_enum)]
        inside: Option<Inside>,
        /// Which 3-D volume of a 4-D volume file to mesh (from 0).
        #[arg(long)]
        volume: Option<usize>,
        /// Coordinate system of meshes of anatomical volumes (written into the file as SPACE=...,
        /// which 3D Slicer reads).
        #[arg(long, value_enum, default_value_t = OutputSpace::Ras)]
        space: OutputSpace,
        /// Seed of the noise fields.
        #[arg(long, default_value_t = fields::DEFAULT_SEED, allow_negative_numbers = true)]
        seed: i32,
        /// Post-process to apply (repeatable).
        #[arg(long)]
        post: Vec<String>,
        /// Surface nets smoothing: none, elastic, spring or implicit (shorthand for --set smoothing=...).
        #[arg(long)]
        smoothing: Option<String>,
        /// Smoothing iterations (shorthand for --set iterations=N).
        #[arg(long, allow_negative_numbers = true)]
        iterations: Option<String>,
        /// bcc-sculpt: lattice spacing h (shorthand for --set spacing=H).
        #[arg(long, allow_negative_numbers = true)]
        spacing: Option<String>,
        /// bcc-sculpt: d_offset / h, where relaxation stops (shorthand for --set offset-ratio=R).
        #[arg(long, allow_negative_numbers = true)]
        offset_ratio: Option<String>,
        /// bcc-sculpt: perturbed lattices to try, keeping the best (shorthand for --set perturbations=K).
        #[arg(long, allow_negative_numbers = true)]
        perturbations: Option<String>,
        /// Mesh in chunks of N cells per side (sharing boundary samples, in parallel) and write the
        /// welded mesh; in memory N must divide the cells along every axis (use --dims k*N+1),
        /// with --stream it need not (the last block on an axis takes what remains).
        #[arg(long)]
        chunk: Option<usize>,
        /// Mesh a volume file block by block as its slices are read, writing the mesh as it goes
        /// (binary .ply output): memory holds one layer of blocks, never the volume (blocks of
        /// --chunk cells, 64 by default, any volume size). The same mesh as --chunk in memory. A
        /// volume too large for memory streams without it when its output is a .ply.
        #[arg(long)]
        stream: bool,
        /// Sample only near the surface, or refuse saying why not. Without --sparse or --dense, a
        /// built-in or mesh field is meshed sparsely wherever its Lipschitz bound certifies it and
        /// the mesh is the dense one (cubic lattice, an algorithm that meshes in blocks, no
        /// --post, --materials or --samples-out): `-f asteroid -r 2048` fits in memory.
        #[arg(long, conflicts_with = "dense")]
        sparse: bool,
        /// Sample every point of the grid.
        #[arg(long)]
        dense: bool,
        /// A Lipschitz bound of the field (|f(p) - f(q)| <= L |p - q|) to prune with, for a field
        /// without one of its own or to replace it; a bound too small loses surface.
        #[arg(long)]
        lipschitz: Option<f64>,
        /// Give every vertex the field's material (the inside sample of its lattice edge): counts
        /// per material in the metrics JSON, vertex colours in the written mesh.
        #[arg(long)]
        materials: bool,
        /// Any algorithm option, NAME=VALUE (repeatable; see the algorithm's module documentation).
        #[arg(long = "set", value_name = "NAME=VALUE", value_parser = parse_option)]
        set: Vec<(String, String)>,
        /// Write the mesh (.obj, .ply, .stl, .glb or .gltf); volume extractors also write their
        /// tetrahedra beside it (same name, .vtk).
        #[arg(long, short)]
        output: Option<PathBuf>,
        /// Measure the mesh (quality, topology, volume, area, distance to the true surface, normal
        /// deviation, overdraw) and write the run's JSON with them here (`-` for stdout). Without
        /// it no mesh metric is computed and stdout gets the run's JSON with its times and counts.
        #[arg(long, short)]
        metrics: Option<PathBuf>,
        /// Also count self-intersecting triangle pairs (exact predicates; many times the
        /// extraction's cost on large meshes). Implies the metrics, on stdout without --metrics.
        #[arg(long)]
        self_intersections: bool,
        /// Write the sampled grid: raw little-endian f32, x fastest (`PATH`), and its dims, origin,
        /// spacing and iso as JSON (`PATH.json`), for running a peer library on the same samples.
        #[arg(long)]
        samples_out: Option<PathBuf>,
    },
    /// Mesh a label map (a segmentation): one closed surface per label; neighbouring labels
    /// share their interface triangles.
    Labels {
        /// The label map: a volume file (.nii, .nii.gz, .nrrd, .nhdr, .mhd, .mha, zarr) of whole-number
        /// labels, 0 the background.
        #[arg(long, short)]
        field: PathBuf,
        /// Label extractor: surface-nets (Frisken 2022, smoothed), marching-tetrahedra
        /// (manifold for every map) or lattice-cleaving (tetrahedra filling every label, dihedral
        /// angles bounded; write them with `-o NAME.vtk` or `-o NAME.msh`); see `isolab list`.
        #[arg(long, short, default_value = "surface-nets")]
        algorithm: String,
        /// The labels to mesh, comma-separated (default: every label but 0); the others count as
        /// background.
        #[arg(long, value_delimiter = ',')]
        labels: Option<Vec<u32>>,
        /// Which 3-D volume of a 4-D file (from 0).
        #[arg(long)]
        volume: Option<usize>,
        /// Coordinate system of the meshes of anatomical label maps.
        #[arg(long, value_enum, default_value_t = OutputSpace::Ras)]
        space: OutputSpace,
        /// Any algorithm option, NAME=VALUE (repeatable): smoothing=none|constrained,
        /// iterations=N, relaxation=L, border=closed|open.
        #[arg(long = "set", value_name = "NAME=VALUE", value_parser = parse_option)]
        set: Vec<(String, String)>,
        /// Where to write: a folder (one mesh file per label, `<name>-label-<n>.<format>`,
        /// created if missing, and `<name>-tetrahedra.vtk` from an algorithm that makes
        /// tetrahedra), a `.glb` file (one named, coloured node per label), a `.vtk` file (the
        /// tetrahedra of lattice-cleaving with their `label` cell array) or a `.msh` file (the
        /// same for Gmsh and finite element codes: MSH 2.2, a physical volume per label).
        #[arg(long, short)]
        output: Option<PathBuf>,
        /// Format of the per-label files in a folder: ply, obj, stl, glb or gltf; or
        /// `neuroglancer`: the folder becomes a neuroglancer precomputed multi-resolution mesh
        /// source (Draco fragments in an octree of blocks, coarser levels simplified);
        /// `neuroglancer-legacy`: the legacy single-resolution format (a float fragment per block).
        #[arg(long, default_value = "ply")]
        format: String,
        /// With `--format neuroglancer`: cells per level-0 fragment box along each axis.
        #[arg(long, default_value_t = 64)]
        chunk: usize,
        /// With `--format neuroglancer`: levels of detail (default: enough that the coarsest is
        /// one box).
        #[arg(long)]
        lods: Option<usize>,
        /// With `--format neuroglancer`: write shards (neuroglancer_uint64_sharded_v1) instead
        /// of two files per label.
        #[arg(long)]
        sharded: bool,
        /// With `--format neuroglancer`: bits per quantized vertex coordinate, 10 or 16.
        #[arg(long, default_value_t = 16)]
        quantization_bits: u32,
        /// Write each label's metrics (closed, manifold, area, volume, triangle shape, triangles
        /// shared with each neighbour) as JSON here (`-` for stdout); without it, stdout gets one
        /// line per label.
        #[arg(long, short)]
        metrics: Option<PathBuf>,
    },
    /// Print the metrics JSON of a mesh file (.obj, .ply, .stl, .glb or .gltf).
    Metrics {
        /// The mesh file.
        file: PathBuf,
    },
    /// Render a mesh file (.obj, .ply, .stl, .glb or .gltf) to a PNG picture, or a turntable GIF.
    Render {
        /// The mesh file.
        file: PathBuf,
        /// Output image: .png (one view) or .gif (a turntable).
        #[arg(long, short)]
        output: PathBuf,
        /// Smooth shading instead of flat.
        #[arg(long)]
        smooth: bool,
        /// Draw triangle edges.
        #[arg(long)]
        wireframe: bool,
        /// Width and height in pixels.
        #[arg(long, default_value_t = 480, value_parser = clap::value_parser!(u32).range(16..=4096))]
        size: u32,
    },
}

fn parse_option(text: &str) -> Result<(String, String), String> {
    text.split_once('=')
        .map(|(k, v)| (k.trim().to_owned(), v.trim().to_owned()))
        .ok_or_else(|| format!("'{text}': expected NAME=VALUE"))
}

fn parse_dims(text: &str) -> Result<[usize; 3], String> {
    let parts: Vec<&str> = text.split([',', 'x']).collect();
    let dims: Vec<usize> = parts
        .iter()
        .map(|p| p.trim().parse::<usize>().map_err(|_| format!("'{text}': '{}' is not a whole number of samples", p.trim())))
        .collect::<Result<_, _>>()?;
    <[usize; 3]>::try_from(dims).map_err(|_| format!("'{text}': expected three numbers, like 75,40,56"))
}

/// `isolab list`: the registry's entries ([`isolab_pipeline::registry`]), a few lines each.
fn list() {
    use isolab_pipeline::registry::{field_listing, listing, EntryKind};
    let entries = listing();
    let headings = [
        (EntryKind::Extractor, "algorithms (options: --set NAME=VALUE):"),
        (EntryKind::PostProcess, "post-processes:"),
        (EntryKind::Labels, "label extractors (isolab labels -a NAME; options: --set NAME=VALUE):"),
    ];
    for (kind, heading) in headings {
        println!("{heading}");
        for e in entries.iter().filter(|e| e.kind == kind) {
            println!("  {:<34} {}", e.name, e.description);
            if !e.options.is_empty() {
                println!("  {:<34} options: {}", "", e.options.join(", "));
            }
            println!("  {:<34} {}", "", e.promises);
        }
    }
    println!(
        "fields (or a path to a mesh file: .obj .ply .stl .glb .gltf; or a volume file: .nii .nii.gz .nrrd .nhdr .mhd .mha .zarr):"
    );
    for f in field_listing() {
        println!("  {:<34} {}", f.name, f.description);
        // What lets a large grid of it be sampled near its surface only (`--sparse`).
        if let Some(l) = f.lipschitz {
            println!("  {:<34} Lipschitz bound {l:.3}: sampled near its surface on large grids", "");
        }
    }
}

/// Set by the CLI when it re-executes itself (see [`with_huge_pages`]), so it does so once.
const REEXECUTED: &str = "ISOLAB_REEXECUTED";

/// Set to anything, keeps the CLI from re-executing itself with huge pages.
const NO_HUGE_PAGES: &str = "ISOLAB_NO_HUGE_PAGES";

/// Re-executes this process with glibc's malloc asking the kernel for transparent huge pages
/// (`GLIBC_TUNABLES=glibc.malloc.hugetlb=1`), unless the caller set `GLIBC_TUNABLES` or
/// [`NO_HUGE_PAGES`] itself. The CLI makes one extraction per process, so its samples and its
/// output land on pages the kernel has never handed out, each 4 KiB page faulted in and zeroed on
/// first touch; with huge pages that is one fault per 2 MiB. The `peers` report measures the CLI
/// with and without them against the library's one-shot call. glibc reads its tunables only at
/// start-up, and the workspace forbids the `unsafe` a `madvise` would need, hence the
/// re-execution. If it fails (no executable path), or glibc is too old to know the tunable, the
/// CLI runs on as it is.
#[cfg(all(target_os = "linux", target_env = "gnu"))]
fn with_huge_pages() {
    use std::os::unix::process::CommandExt;
    let set = |name: &str| std::env::var_os(name).is_some();
    if set("GLIBC_TUNABLES") || set(NO_HUGE_PAGES) || set(REEXECUTED) {
        return;
    }
    let Ok(exe) = std::env::current_exe() else { return };
    let mut args = std::env::args_os();
    let arg0 = args.next().unwrap_or_else(|| exe.clone().into_os_string());
    // `exec` returns only if it failed; then this process carries on as it is.
    let _failed = std::process::Command::new(&exe)
        .arg0(arg0)
        .args(args)
        .env("GLIBC_TUNABLES", "glibc.malloc.hugetlb=1")
        .env(REEXECUTED, "1")
        .exec();
}

#[cfg(not(all(target_os = "linux", target_env = "gnu")))]
fn with_huge_pages() {}

fn main() -> ExitCode {
    with_huge_pages();
    let cli = Cli::parse();
    let result: Result<(), (i32, String)> = match cli.command {
        Command::List => {
            list();
            Ok(())
        }
        Command::Extract {
            algorithm,
            field,
            resolution,
            dims,
            lattice,
            iso,
            inside,
            volume,
            space,
            seed,
            post,
            smoothing,
            iterations,
            spacing,
            offset_ratio,
            perturbations,
            chunk,
            stream,
            sparse,
            dense,
            lipschitz,
            materials,
            set,
            output,
            metrics,
            self_intersections,
            samples_out,
        } => {
            let shorthands = [
                ("smoothing", smoothing),
                ("iterations", iterations),
                ("spacing", spacing),
                ("offset-ratio", offset_ratio),
                ("perturbations", perturbations),
            ];
            let config = RunConfig::builder(&algorithm, &field)
                .resolution(resolution)
                .dims(dims)
                .lattice(lattice)
                .iso(iso)
                .inside(inside)
                .volume(volume)
                .space(space)
                .seed(seed)
                .post(post)
                .options(set)
                .options(shorthands.into_iter().filter_map(|(k, v)| Some((k, v?))))
                .chunk(chunk)
                .materials(materials)
                .measure(Measure::asked(metrics.is_some(), self_intersections))
                // --samples-out needs every sample.
                .sparse(Sparse::asked(sparse, dense || samples_out.is_some()))
                .lipschitz(lipschitz)
                .build();
            extract(&config, stream, output, metrics, samples_out).map_err(|e| (e.exit_code(), e.to_string()))
        }
        Command::Labels {
            field,
            algorithm,
            labels: select,
            volume,
            space,
            set,
            output,
            format,
            chunk,
            lods,
            sharded,
            quantization_bits,
            metrics,
        } => {
            let mut options = isolab_algorithms::Options::new();
            for (k, v) in &set {
                options.set(k, v);
            }
            let config = isolab_pipeline::labels::LabelConfig { algorithm, options, select, space };
            let neuroglancer = labels::NeuroglancerJob { chunk, lods, sharded, bits: quantization_bits };
            let job = labels::Job { input: field, volume, config, output, format, neuroglancer, metrics };
            labels::run(&job).map_err(|e| (e.exit_code(), e.to_string()))
        }
        Command::Metrics { file } => isolab_pipeline::files::read_mesh_file(&file)
            .map(|mesh| {
                let m = MeshMetrics::measure(&mesh, None);
                println!("{}", serde_json::to_string_pretty(&m).unwrap_or_default());
            })
            .map_err(|e| (2, e.to_string())),
        Command::Render { file, output, smooth, wireframe, size } => render(&file, &output, smooth, wireframe, size),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err((code, message)) => {
            eprintln!("error: {message}");
            ExitCode::from(code as u8)
        }
    }
}

fn render(
    file: &std::path::Path,
    output: &std::path::Path,
    smooth: bool,
    wireframe: bool,
    size: u32,
) -> Result<(), (i32, String)> {
    use isolab_render::{self as render, RenderOptions, Shading};
    let mesh = isolab_pipeline::files::read_mesh_file(file).map_err(|e| (2, e.to_string()))?;
    let bad = mesh.positions.iter().filter(|p| !p.is_finite()).count();
    if bad > 0 {
        return Err((
            1,
            format!(
                "'{}': {bad} {} not finite (NaN or infinite); cannot frame the picture",
                file.display(),
                if bad == 1 { "vertex is" } else { "vertices are" }
            ),
        ));
    }
    let opts = RenderOptions {
        width: size,
        height: size,
        shading: if smooth { Shading::Smooth } else { Shading::Flat },
        wireframe,
        ..Default::default()
    };
    let ext = output.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
    let result = match ext.as_deref() {
        Some("png") => render::save_png(output, &render::render(&mesh, &opts)),
        Some("gif") => render::save_turntable(output, &mesh, &opts, 36, 8),
        _ => Err(io::IoError::UnknownFormat { path: output.to_path_buf() }),
    };
    result.map_err(|e| (1, e.to_string()))
}

/// `--stream`: the volume file meshed block by block into `output`, the run's JSON to `metrics`
/// or stdout, a progress line on a terminal's stderr.
fn stream_volume(config: &RunConfig, output: &std::path::Path, metrics: Option<&std::path::Path>) -> Result<(), RunError> {
    use std::io::IsTerminal;
    let terminal = std::io::stderr().is_terminal();
    let mut progress = |done: usize, total: usize| {
        if terminal {
            eprint!("\rstreaming: layer {done} of {total} of blocks");
            if done == total {
                eprintln!();
            }
        }
    };
    let report = isolab_pipeline::stream::stream_volume_file(config, output, &mut progress)?;
    for note in &report.notes {
        eprintln!("note: {note}");
    }
    for warning in &report.warnings {
        eprintln!("warning: {warning}");
    }
    match metrics {
        Some(path) => write_json(path, &report)?,
        None => println!("{}", serde_json::to_string_pretty(&report).unwrap_or_default()),
    }
    Ok(())
}

fn extract(
    config: &RunConfig,
    stream: bool,
    output: Option<PathBuf>,
    metrics: Option<PathBuf>,
    samples_out: Option<PathBuf>,
) -> Result<(), RunError> {
    // Refuse unwritable outputs before spending time on extraction.
    isolab_pipeline::files::check_outputs(output.as_deref(), metrics.iter().chain(samples_out.iter()).map(PathBuf::as_path))?;
    let metrics = metrics.filter(|p| p.as_os_str() != "-");
    if config.sparse == Sparse::Always && samples_out.is_some() {
        let reason = "--samples-out needs every sample (drop --sparse)".into();
        return Err(RunError::Sparse { field: config.field.clone(), reason });
    }
    if stream {
        let Some(path) = &output else {
            return Err(RunError::Stream { path: config.field.clone(), reason: "a streamed mesh needs -o NAME.ply".into() });
        };
        if samples_out.is_some() {
            let reason = "a streamed run does not take --samples-out (it never holds the samples)".into();
            return Err(RunError::Stream { path: config.field.clone(), reason });
        }
        return stream_volume(config, path, metrics.as_deref());
    }
    let outcome = match run(config) {
        Err(RunError::OutOfMemory { need_mib, available_mib, .. })
            if samples_out.is_none()
                && output.as_ref().is_some_and(|o| isolab_pipeline::stream::check_streamable(config, o).is_ok()) =>
        {
            eprintln!(
                "note: {} needs about {need_mib} MiB in memory ({available_mib} MiB available): streaming it block by \
                 block instead (--stream)",
                config.field
            );
            return stream_volume(config, output.as_deref().unwrap_or(std::path::Path::new("")), metrics.as_deref());
        }
        Err(RunError::Extract(e @ isolab_algorithms::ExtractError::OverMemory { .. }))
            if samples_out.is_none()
                && output.as_ref().is_some_and(|o| isolab_pipeline::stream::check_streamable(config, o).is_ok()) =>
        {
            eprintln!("note: {e}: streaming it block by block instead (--stream)");
            return stream_volume(config, output.as_deref().unwrap_or(std::path::Path::new("")), metrics.as_deref());
        }
        other => other?,
    };
    for note in &outcome.notes {
        eprintln!("note: {note}");
    }
    for warning in &outcome.report.warnings {
        eprintln!("warning: {warning}");
    }
    if let Some(path) = &output {
        outcome.write_meshes(path)?;
    }
    if let (Some(path), Some(samples)) = (&samples_out, &outcome.samples) {
        io::write_samples(path, samples, outcome.samples_to_world.as_ref())?;
    }
    match &metrics {
        Some(path) => write_json(path, &outcome.report)?,
        None => println!("{}", serde_json::to_string_pretty(&outcome.report).unwrap_or_default()),
    }
    Ok(())
}
