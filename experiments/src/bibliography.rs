//! The report's bibliography (`report/bibliography.md`): every paper and post the extractors
//! follow and the pages reproduce, with authors, title, venue, year and DOI where one is known.
//! The entries repeat what the modules that use them cite (their module docs are where each was
//! read); a test holds the two together: every DOI a module of `algorithms/` quotes is here, and
//! every DOI here is quoted by the module that uses it. The posts and theses are kept as the
//! copies the project was specified from (`../shared/papers/`), which name no URL.

/// One work.
pub struct Work {
    /// Its anchor on the page (`#key`).
    pub key: &'static str,
    /// Authors as the work names them.
    pub authors: &'static str,
    /// Title.
    pub title: &'static str,
    /// Where it appeared.
    pub venue: &'static str,
    /// Year.
    pub year: u16,
    /// Its DOI, or `None` where the modules that use it record none.
    pub doi: Option<&'static str>,
    /// What in isolab follows it.
    pub used_by: &'static str,
}

/// Every work, by year.
pub const WORKS: &[Work] = &[
    Work {
        key: "lorensen-1987",
        authors: "W. E. Lorensen, H. E. Cline",
        title: "Marching cubes: a high resolution 3D surface construction algorithm",
        venue: "SIGGRAPH 1987",
        year: 1987,
        doi: Some("10.1145/37402.37422"),
        used_by: "`marching-cubes` and its table",
    },
    Work {
        key: "payne-1990",
        authors: "A. Payne, A. W. Toga",
        title: "Surface mapping brain function on 3D models",
        venue: "IEEE Computer Graphics and Applications 10(5)",
        year: 1990,
        doi: None,
        used_by: "`marching-tetrahedra`",
    },
    Work {
        key: "nielson-1991",
        authors: "G. M. Nielson, B. Hamann",
        title: "The asymptotic decider: resolving the ambiguity in marching cubes",
        venue: "IEEE Visualization 1991",
        year: 1991,
        doi: Some("10.1109/VISUAL.1991.175782"),
        used_by: "`marching-cubes-decider`",
    },
    Work {
        key: "chernyaev-1995",
        authors: "E. V. Chernyaev",
        title: "Marching cubes 33: construction of topologically correct isosurfaces",
        venue: "CERN report CN/95-17",
        year: 1995,
        doi: None,
        used_by: "`marching-cubes-33`",
    },
    Work {
        key: "gibson-1998",
        authors: "S. F. F. Gibson",
        title: "Constrained elastic surface nets: generating smooth surfaces from binary segmented data",
        venue: "MICCAI 1998",
        year: 1998,
        doi: Some("10.1007/BFb0056277"),
        used_by: "`surface-nets`",
    },
    Work {
        key: "treece-1999",
        authors: "G. M. Treece, R. W. Prager, A. H. Gee",
        title: "Regularised marching tetrahedra: improved iso-surface extraction",
        venue: "Computers & Graphics 23(4)",
        year: 1999,
        doi: Some("10.1016/S0097-8493(99)00076-X"),
        used_by: "`regularised-marching-tetrahedra`",
    },
    Work {
        key: "ju-2002",
        authors: "T. Ju, F. Losasso, S. Schaefer, J. Warren",
        title: "Dual contouring of Hermite data",
        venue: "SIGGRAPH 2002",
        year: 2002,
        doi: Some("10.1145/566654.566586"),
        used_by: "`dual-contouring`",
    },
    Work {
        key: "lewiner-2003",
        authors: "T. Lewiner, H. Lopes, A. W. Vieira, G. Tavares",
        title: "Efficient implementation of marching cubes' cases with topological guarantees",
        venue: "Journal of Graphics Tools 8(2)",
        year: 2003,
        doi: Some("10.1080/10867651.2003.10487582"),
        used_by: "`marching-cubes-33`, and the drop-in's `method=\"lewiner\"`",
    },
    Work {
        key: "nielson-2003",
        authors: "G. M. Nielson",
        title: "On marching cubes",
        venue: "IEEE Transactions on Visualization and Computer Graphics 9(3)",
        year: 2003,
        doi: Some("10.1109/TVCG.2003.1207437"),
        used_by: "`marching-cubes-33`'s tunnels through the interpolant's waist",
    },
    Work {
        key: "alliez-2005",
        authors: "P. Alliez et al.",
        title: "Variational tetrahedral meshing",
        venue: "SIGGRAPH 2005",
        year: 2005,
        doi: None,
        used_by: "`bcc-sculpt`'s ODT relaxation",
    },
    Work {
        key: "ju-2006",
        authors: "T. Ju, T. Udeshi",
        title: "Intersection-free contouring on an octree grid",
        venue: "Pacific Graphics 2006",
        year: 2006,
        doi: None,
        used_by: "`manifold-dual-contouring`",
    },
    Work {
        key: "schaefer-2007",
        authors: "S. Schaefer, T. Ju, J. Warren",
        title: "Manifold dual contouring",
        venue: "IEEE Transactions on Visualization and Computer Graphics 13(3)",
        year: 2007,
        doi: Some("10.1109/TVCG.2007.1012"),
        used_by: "`manifold-dual-contouring`",
    },
    Work {
        key: "labelle-2007",
        authors: "F. Labelle, J. R. Shewchuk",
        title: "Isosurface stuffing: fast tetrahedral meshes with good dihedral angles",
        venue: "ACM Transactions on Graphics 26(3), SIGGRAPH 2007",
        year: 2007,
        doi: None,
        used_by: "`isosurface-stuffing`; compared in `quality_tets`",
    },
    Work {
        key: "custodio-2013",
        authors: "L. Custodio, T. Etiene, S. Pesco, C. Silva",
        title: "Practical considerations on Marching Cubes 33 topological correctness",
        venue: "Computers & Graphics",
        year: 2013,
        doi: Some("10.1016/j.cag.2013.04.004"),
        used_by: "`marching-cubes-33`'s table",
    },
    Work {
        key: "jacobson-2013",
        authors: "A. Jacobson, L. Kavan, O. Sorkine-Hornung",
        title: "Robust inside-outside segmentation using generalized winding numbers",
        venue: "SIGGRAPH 2013",
        year: 2013,
        doi: Some("10.1145/2461912.2461916"),
        used_by: "mesh files as fields (the inside of an open or self-intersecting mesh)",
    },
    Work {
        key: "museth-2013",
        authors: "K. Museth",
        title: "VDB: high-resolution sparse volumes with dynamic topology",
        venue: "ACM Transactions on Graphics 32(3)",
        year: 2013,
        doi: Some("10.1145/2487228.2487235"),
        used_by: "mesh fields' narrow band (`mesh_fields`)",
    },
    Work {
        key: "stuart-2013",
        authors: "D. A. Stuart, J. A. Levine, B. Jones, A. W. Bargteil",
        title: "Automatic construction of coarse, high-quality tetrahedralizations that enclose and approximate surfaces \
                for animation",
        venue: "MIG '13",
        year: 2013,
        doi: None,
        used_by: "`bcc-sculpt`; reproduced in `stuart_tables`, compared in `quality_tets`",
    },
    Work {
        key: "schroeder-2015",
        authors: "W. Schroeder, R. Maynard, B. Geveci",
        title: "Flying edges: a high-performance scalable isocontouring algorithm",
        venue: "IEEE LDAV 2015",
        year: 2015,
        doi: Some("10.1109/LDAV.2015.7348069"),
        used_by: "`marching-cubes`' row trimming",
    },
    Work {
        key: "barill-2018",
        authors: "G. Barill et al.",
        title: "Fast winding numbers for soups and clouds",
        venue: "SIGGRAPH 2018",
        year: 2018,
        doi: Some("10.1145/3197517.3201337"),
        used_by: "mesh fields' winding numbers far from the mesh",
    },
    Work {
        key: "svoboda-2020",
        authors: "W. Svoboda (adviser S. Rusinkiewicz)",
        title: "Improving the marching cubes algorithm for use in deformable 3D terrain",
        venue: "independent work project, copy in `shared/papers/svoboda-2020-marching-cubes-deformable-terrain.txt`",
        year: 2020,
        doi: None,
        used_by: "reproduced in `svoboda_timing`",
    },
    Work {
        key: "frisken-2022",
        authors: "S. F. Frisken",
        title: "SurfaceNets for multi-label segmentations with preservation of sharp boundaries",
        venue: "Journal of Computer Graphics Techniques 11(1)",
        year: 2022,
        doi: None,
        used_by: "`isolab labels -a surface-nets` (`segmentations`)",
    },
    Work {
        key: "mesh-generation-post-2024",
        authors: "author not named in our copy",
        title: "Mesh Generation (marching cubes terrain with materials and liquids)",
        venue: "blog post, copy in `shared/papers/blog-marching-cubes-terrain-materials.txt`",
        year: 2024,
        doi: None,
        used_by: "`--materials`, liquids (`terrain_liquids`)",
    },
    Work {
        key: "surface-nets-post",
        authors: "author not named in our copy",
        title: "untitled in our copy: mesh generation for a 3D terrain with surface nets",
        venue: "blog post (undated), copy in `shared/papers/blog-surface-nets-terrain.txt`",
        year: 0,
        doi: None,
        used_by: "`surface-nets`' smoothing (`surface_nets_smoothing`)",
    },
    Work {
        key: "costen-2026",
        authors: "C. Costen (supervised by K. Osborne)",
        title: "An examination of isosurface extraction for 3D terrain generation in videogames",
        venue: "Staffordshire University, copy in `shared/papers/costen-2026-rmt-terrain.txt`",
        year: 2026,
        doi: None,
        used_by: "the tetrahedral lattices and clustering; reproduced in `costen_table`",
    },
];

/// The line a page gives its sources: every work whose `used_by` names the experiment (`` `name` ``),
/// linked to its entry; `None` when none does.
pub fn sources_of(experiment: &str) -> Option<String> {
    let named = format!("`{experiment}`");
    let links: Vec<String> = WORKS
        .iter()
        .filter(|w| w.used_by.contains(&named))
        .map(|w| format!("[{}](bibliography.md#{})", w.title, w.key))
        .collect();
    (!links.is_empty()).then(|| format!("Sources: {}.", links.join("; ")))
}

/// The bibliography page.
pub fn page() -> String {
    let mut md = String::from(
        "[isolab report](REPORT.md) › Bibliography\n\n# Bibliography\n\nThe papers and posts isolab's extractors follow \
         and its pages reproduce, as the modules that use them cite them. A DOI links the work; where none is given, the \
         modules record none (posts and theses are kept as the copies the project was specified from).\n\n",
    );
    for w in WORKS {
        // The year, unless the venue already names it ("SIGGRAPH 1987").
        let year = match w.year {
            0 => ", undated".to_owned(),
            y if w.venue.contains(&y.to_string()) => String::new(),
            y => format!(", {y}"),
        };
        let doi = w.doi.map_or(String::new(), |d| format!(" DOI [{d}](https://doi.org/{d})."));
        md.push_str(&format!(
            "- <a id=\"{}\"></a>{}, \"{}\", {}{year}.{doi} Used by: {}.\n",
            w.key, w.authors, w.title, w.venue, w.used_by
        ));
    }
    md
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::{Path, PathBuf};

    fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
        for entry in std::fs::read_dir(dir).expect("a source folder") {
            let path = entry.expect("entry").path();
            if path.is_dir() {
                rust_files(&path, out);
            } else if path.extension().is_some_and(|e| e == "rs") {
                out.push(path);
            }
        }
    }

    /// The DOIs a text quotes (`DOI 10.x/y`, the line break between the two allowed).
    fn dois(text: &str) -> Vec<String> {
        let flat = text.replace("\n//! ", " ").replace("\n/// ", " ");
        flat.split("DOI")
            .skip(1)
            .filter_map(|rest| rest.split_whitespace().next())
            .map(|d| d.trim_end_matches(['.', ',', ';', ')', ':']).to_owned())
            .filter(|d| d.starts_with("10."))
            .collect()
    }

    #[test]
    fn every_doi_the_algorithms_quote_is_listed_and_every_listed_one_is_quoted() {
        let mut files = Vec::new();
        rust_files(&Path::new(env!("CARGO_MANIFEST_DIR")).join("../algorithms/src"), &mut files);
        let quoted: std::collections::BTreeSet<String> =
            files.iter().flat_map(|f| dois(&std::fs::read_to_string(f).expect("source"))).collect();
        assert!(quoted.len() >= 10, "{quoted:?}");
        let listed: std::collections::BTreeSet<String> = WORKS.iter().filter_map(|w| w.doi.map(str::to_owned)).collect();
        let missing: Vec<&String> = quoted.difference(&listed).collect();
        assert!(missing.is_empty(), "quoted in algorithms/ but not in the bibliography: {missing:?}");
        let unquoted: Vec<&String> = listed.difference(&quoted).collect();
        assert!(unquoted.is_empty(), "in the bibliography but quoted by no module of algorithms/: {unquoted:?}");
    }

    #[test]
    fn the_page_lists_every_work_once_by_year_with_an_anchor() {
        let page = page();
        for w in WORKS {
            assert_eq!(page.matches(&format!("<a id=\"{}\"></a>", w.key)).count(), 1, "{}", w.key);
        }
        let dated: Vec<u16> = WORKS.iter().map(|w| w.year).filter(|&y| y > 0).collect();
        assert!(dated.windows(2).all(|p| p[0] <= p[1]), "not by year: {dated:?}");
        assert_eq!(dois("a (DOI 10.1/x), and DOI\n//! 10.2/y."), ["10.1/x", "10.2/y"]);
        let costen = sources_of("costen_table").expect("costen_table reproduces a paper");
        assert!(costen.contains("(bibliography.md#costen-2026)"), "{costen}");
        assert_eq!(sources_of("viewer"), None);
    }
}
