//! The man pages in `man/` and the shell completions in `man/completions/` are generated from the
//! clap definitions; this test fails when they are stale. Regenerate with
//! `PGO_BLESS=1 cargo test --test man`.

use std::path::PathBuf;

fn check_or_bless(path: PathBuf, generated: Vec<u8>, stale: &mut Vec<String>) {
    if std::env::var_os("PGO_BLESS").is_some() {
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(&path, &generated).unwrap();
        return;
    }
    if std::fs::read(&path).ok().as_deref() != Some(&generated[..]) {
        stale.push(path.display().to_string());
    }
}

#[test]
fn man_pages_and_completions_are_up_to_date() {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("man");
    let mut stale = Vec::new();
    for cmd in pgo::cli::commands() {
        let name = cmd.get_name().to_string();
        let mut page = Vec::new();
        clap_mangen::Man::new(cmd.clone())
            .render(&mut page)
            .unwrap();
        check_or_bless(root.join(format!("{name}.1")), page, &mut stale);
        for (shell, ext) in [
            (clap_complete::Shell::Bash, "bash"),
            (clap_complete::Shell::Zsh, "zsh"),
            (clap_complete::Shell::Fish, "fish"),
        ] {
            let mut script = Vec::new();
            clap_complete::generate(shell, &mut cmd.clone(), name.clone(), &mut script);
            check_or_bless(
                root.join("completions").join(format!("{name}.{ext}")),
                script,
                &mut stale,
            );
        }
    }
    assert!(
        stale.is_empty(),
        "stale generated files (regenerate with `PGO_BLESS=1 cargo test --test man`): {stale:?}"
    );
}
