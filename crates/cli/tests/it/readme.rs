//! The README and docs say what the code does: the n_max defaults are the constants, the new
//! options are documented, and nothing points outside the repository.

use std::path::Path;

fn read(rel: &str) -> String {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    std::fs::read_to_string(root.join(rel)).unwrap_or_else(|e| panic!("{rel}: {e}"))
}

#[test]
fn readme_states_the_n_max_defaults_of_the_code() {
    let readme = read("README.md");
    for (name, value) in [
        (
            "partition_sampler::TreeParams::DEFAULT_N_MAX",
            partition_sampler::TreeParams::DEFAULT_N_MAX,
        ),
        (
            "brdf_sampling::SetOptions::DEFAULT_N_MAX",
            brdf_sampling::SetOptions::DEFAULT_N_MAX,
        ),
        (
            "envmap::AdaptiveOptions::DEFAULT_N_MAX",
            envmap::AdaptiveOptions::DEFAULT_N_MAX,
        ),
    ] {
        let stated = format!("`{name}` = {value:?}");
        assert!(readme.contains(&stated), "README lacks `{stated}`");
    }
}

#[test]
fn readme_documents_the_user_facing_behaviour() {
    let readme = read("README.md");
    for needle in [
        "envmap -n 1000000 --compare",
        "--set FILE",
        "--grid",
        "BRDF_LAB_PROGRESS_SECS",
        "brdf-lab: warning:",
        "normalised",
        "reference",
        "--example merl -- --out",
        "standard error",
    ] {
        assert!(
            readme.contains(needle),
            "README does not mention `{needle}`"
        );
    }
}

#[test]
fn docs_do_not_point_outside_the_repository() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let mut files = vec![root.join("README.md"), root.join("ARCHITECTURE.md")];
    for e in std::fs::read_dir(root.join("docs"))
        .expect("docs")
        .flatten()
    {
        if e.path().extension().is_some_and(|x| x == "md") {
            files.push(e.path());
        }
    }
    for f in files {
        let text = std::fs::read_to_string(&f).expect("doc");
        assert!(
            !text.contains("../shared"),
            "{} points to ../shared",
            f.display()
        );
    }
}

#[test]
fn default_outputs_are_ignored_by_git() {
    let ignore = read(".gitignore");
    for default in ["study-out/", "/target"] {
        assert!(
            ignore.lines().any(|l| l.trim() == default),
            ".gitignore lacks {default}"
        );
    }
}
