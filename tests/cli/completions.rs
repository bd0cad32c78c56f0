//! `whitted completions SHELL` and `whitted man`: scripts every shell is given, the bash script run by
//! bash to complete a subcommand and an option, and the man pages rendered by `man`.

use std::process::Command;

use crate::common;

/// The subcommands of every build (`view` is the viewer feature's).
const SUBCOMMANDS: [&str; 6] = ["info", "render", "bench", "merge", "completions", "man"];

#[test]
fn every_shell_gets_a_script_naming_the_subcommands() {
    for shell in ["bash", "zsh", "fish", "powershell", "elvish"] {
        let script = common::stdout(&["completions", shell]);
        assert!(!script.trim().is_empty(), "{shell}: an empty script");
        for sub in SUBCOMMANDS {
            assert!(script.contains(sub), "{shell}: `{sub}` is not in the script");
        }
    }
}

/// What bash's completion offers for the command line `words` (the last word the one being
/// completed), from the script `whitted completions bash` prints, called as bash's `complete` would.
fn bash_completes(words: &[&str]) -> Vec<String> {
    let dir = tempfile::tempdir().unwrap();
    let script = dir.path().join("whitted.bash");
    std::fs::write(&script, common::stdout(&["completions", "bash"])).unwrap();
    let driver = r#"
        source "$1"; shift
        spec=$(complete -p whitted) || exit 1
        function=${spec#*-F }; function=${function%% *}
        COMP_WORDS=("$@")
        COMP_CWORD=$((${#COMP_WORDS[@]} - 1))
        COMP_LINE="${COMP_WORDS[*]}"
        COMP_POINT=${#COMP_LINE}
        "$function" whitted "${COMP_WORDS[COMP_CWORD]}" "${COMP_WORDS[COMP_CWORD - 1]}"
        printf '%s\n' "${COMPREPLY[@]}"
    "#;
    let out = Command::new("bash")
        .args(["--norc", "--noprofile", "-c", driver, "bash"])
        .arg(&script)
        .args(words)
        .output()
        .expect("bash runs");
    let stdout = String::from_utf8(out.stdout).unwrap();
    assert!(
        out.status.success(),
        "{stdout}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let mut replies: Vec<String> = stdout.split_whitespace().map(str::to_owned).collect();
    replies.sort();
    replies
}

#[test]
fn bash_completes_a_subcommand_and_an_option() {
    assert_eq!(bash_completes(&["whitted", "ren"]), ["render"]);
    // `render`'s options that begin with --sp: the samples a pixel and the SPD procedure.
    assert_eq!(bash_completes(&["whitted", "render", "--sp"]), ["--spd", "--spp"]);
}

/// `page` as `man -l` renders it for an 80-column terminal.
fn man_renders(page: &str) -> String {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("whitted.1");
    std::fs::write(&file, page).unwrap();
    let out = Command::new("man")
        .arg("-l")
        .arg(&file)
        .env("MANPAGER", "cat")
        .env("MANWIDTH", "80")
        .output()
        .expect("man runs");
    let text = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(
        out.status.success(),
        "{text}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    text
}

#[test]
fn man_pages_render() {
    if !common::have("man", &["--version"], "apt-get install man-db") {
        return;
    }
    let text = man_renders(&common::stdout(&["man"]));
    assert!(text.contains("NAME") && text.contains("SYNOPSIS"), "{text}");
    for word in ["whitted", "--version"] {
        assert!(text.contains(word), "`{word}` is not in the page:\n{text}");
    }
    for sub in SUBCOMMANDS {
        assert!(
            text.contains(&format!("whitted-{sub}(1)")),
            "`{sub}` is not listed:\n{text}"
        );
    }
    // No page is listed for clap's `help` subcommand: there is none.
    assert!(!text.contains("whitted-help"), "{text}");

    let text = man_renders(&common::stdout(&["man", "render"]));
    for word in ["whitted-render", "whitted render", "--spp"] {
        assert!(text.contains(word), "`{word}` is not in render's page:\n{text}");
    }

    let err = common::fails(&["man", "rendr"], 2);
    assert!(err.contains("`rendr` is not a subcommand"), "{err}");
}
