//! The literals of the experiments' prose that `report_check` was asked to pass, each with the
//! reason it is not a typed number or verdict: a definition, a place on the page, a setting, a
//! category whose members the data list.

/// Whether a reviewed entry's place names the file `rel` (relative to `experiment/`): the file
/// itself, or a folder ending in `/` holding it (a literal the run and the page both use).
pub(crate) fn names_file(place: &str, rel: &str) -> bool {
    place == rel || (place.ends_with('/') && rel.starts_with(place))
}

/// Reviewed literals whose numbers are not measurements: (file or experiment folder, fragment of
/// the literal, why).
pub(crate) const REVIEWED: &[(&str, &str, &str)] = &[
    ("compare_algorithms/mod.rs", "(1 is ideal)", "a plot axis: the measure's ideal value, by its definition"),
    (
        "compare_algorithms/page.rs",
        "when GPUs shade 2x2 quads",
        "how GPUs shade (2x2 pixel quads) and the measure's ideal value, by definition",
    ),
    (
        "sphere_convergence/page.rs",
        "4/3 π r³ and 4 π r²",
        "the sphere's volume and area formulas, and the slope second-order convergence has",
    ),
    (
        "python_users/",
        "glibc.malloc.hugetlb=",
        "the glibc tunable that asks for huge pages: a setting's name and value, not a result",
    ),
    (
        "python_users/page.rs",
        "faults once per 2 MiB instead of once per 4 KiB",
        "the x86-64 kernel's huge and base page sizes, by definition",
    ),
    (
        "distributed/page.rs",
        "bound to \\\n         127.0.0.1",
        "the loopback address the cluster listens on: a setting, not a result",
    ),
    ("distributed/page.rs", "tls://scheduler:8786", "distributed's default scheduler port in an example address"),
    ("terrain_lod/mod.rs", "2.0.0", "the transvoxel crate's version the peer is built with (Cargo.toml's): a name, not a result"),
    (
        "scaling/page.rs",
        "A slope near 1 means",
        "the slopes that cost proportional to cells (1) and to surface area (2/3) have, by definition",
    ),
];

/// Reviewed literals that state a comparison without data: (file, fragment, why it is not a
/// verdict).
pub(crate) const REVIEWED_COMPARISONS: &[(&str, &str, &str)] = &[
    ("real_volumes/", "the voxels above the first level", "a place (the voxels brighter than a level), not a verdict"),
    ("real_volumes/", "above one when isolab is", "how to read the ratio column, by its definition"),
    ("real_volumes/page.rs", "Inside is above the", "which side is inside: a setting (`--inside above`), not a verdict"),
    ("real_volumes/second.rs", "the meshes \\\n         below overlay", "a place on the page"),
    ("stuart_tables/checks.rs", "from the rows above", "a place on the page"),
    ("functions/page.rs", "its refinement's below the blocks", "a place (the octree refined inside the blocks), not a verdict"),
    (
        "stuart_tables/table_two.rs",
        "claim of the fewest elements is not reproduced",
        "the branch taken when the data counts CGAL fewer on some model (`ours_fewer > 0`)",
    ),
    ("stuart_tables/table_two.rs", "is below ours", "a count the data make (`matched_lower` of `matched_n` models)"),
    ("stuart_tables/page.rs", "a tetrahedron it changes below", "the `quality-floor` threshold, by its definition"),
    ("stuart_tables/reading.rs", "a tetrahedron below {floor}°", "the `quality-floor` threshold, by its definition"),
    ("stuart_tables/relaxation.rs", "smallest dihedral angle below", "the sliver bound, by its definition"),
    ("stuart_tables/relaxation.rs", "fell below {floor}°", "the runs the data put under the floor, counted beside the word"),
    ("compare_algorithms/mod.rs", "lower and to the left is better", "how to read the plot's axes, by their definition"),
    ("decimation/page.rs", "lower and to \\\n         the left is better", "how to read the plot's axes, by their definition"),
    ("surface_nets_smoothing/page.rs", "(lower is better shaped)", "what the aspect ratio measures, by its definition"),
    (
        "surface_nets_smoothing/page.rs",
        "Not reproduced, and not fully explained",
        "the post's ratios are Unity C# on unstated hardware at an unstated iteration count, so they are not \
         reproducible by construction; the one comparable claim, the order, is judged in the same sentence by the data",
    ),
    ("terrain_lod/page.rs", "better shaped (lower mean aspect ratio) on", "a count the data make (`better_shaped` of the pairs)"),
    ("sphere_convergence/page.rs", "Below the exact volume at every resolution", "a category whose members the data list"),
    ("sphere_convergence/page.rs", "Above it at every resolution", "a category whose members the data list"),
    ("costen_table/sphere_match.rs", "is below the paper's in", "a category whose members the data list (`below`)"),
    ("costen_table/sphere_match.rs", "It is above the paper's in", "a category whose members the data list (`above`)"),
    (
        "costen_table/questionnaire.rs",
        "reproduces it (largest difference",
        "the column the search over left-out columns found, its difference printed beside the word",
    ),
    (
        "costen_table/reading.rs",
        "the sphere matches its",
        "points to the section (*Matching the paper's sphere*) whose data test it",
    ),
    ("peers/page.rs", "(above one means we are faster)", "how to read the ratio column, by its definition"),
    ("peers/page.rs", "Above one, the CLI is slower", "how to read the ratio column, by its definition"),
    ("peers/reading.rs", "(the peer faster on {})", "a category whose members the data list (`below`)"),
    ("peers/reading.rs", "(slower with it on {})", "a category whose members the data list (`below`)"),
    ("python_users/page.rs", "faster than ours on every one: {}; slower on every one", "categories whose members the data list"),
    (
        "python_users/targets.rs",
        "at least {VTK_TARGET}× faster than",
        "the issue's target, by its definition; met and missed are counted",
    ),
    ("python_users/targets.rs", "MiB above the input", "a measured amount over the input's size, printed beside the word"),
    ("scaling/mod.rs", "{} above {n}³", "the grids past a size the budget skipped: a place in the sweep"),
    ("large_world/page.rs", "wholly above the ground, or below", "places in the terrain, not verdicts"),
    ("mesh_fields/page.rs", "not bounded below", "a bound in the winding number's definition"),
    ("connectomics/page.rs", "the eight below it", "a place in the octree of boxes"),
    (
        "large_world/reading.rs",
        "its peak resident memory not above the",
        "chosen by `peak_phrase` from the peak against the baseline (tested both ways)",
    ),
    (
        "large_world/reading.rs",
        "MiB above the process's before the run",
        "a measured amount over the baseline, printed beside the word, chosen by `peak_phrase`",
    ),
];
