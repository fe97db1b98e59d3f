//! Finding and naming the programs a run starts: the rig's own binaries beside the running executable, a user's
//! `--controller-cmd` split into words as a shell would (and a word quoted for one), and a program looked up on
//! PATH.

use anyhow::Context;
use std::path::{Path, PathBuf};

/// Folder of the rig binaries: next to the running executable (`target/release/` in a build tree).
pub fn binary_dir() -> anyhow::Result<PathBuf> {
    let exe = std::env::current_exe().context("locating the running executable")?;
    Ok(exe.parent().context("the executable has no folder")?.to_path_buf())
}

/// Split a `--controller-cmd` into words as a POSIX shell would (blanks separate words; single quotes keep
/// everything; double quotes keep everything but `\"`, `\\`, `\$` and `` \` ``; a backslash outside quotes keeps the
/// next character). The program is then run directly, not through a shell, so the signals the rig sends (SIGTERM
/// at the end, the plan's faults) reach it and not a shell in between.
pub fn split_command(cmd: &str) -> Result<Vec<String>, String> {
    let mut words = Vec::new();
    let mut word: Option<String> = None;
    let mut chars = cmd.chars();
    while let Some(c) = chars.next() {
        match c {
            ' ' | '\t' | '\n' => words.extend(word.take()),
            '\'' => {
                let w = word.get_or_insert_with(String::new);
                loop {
                    match chars.next() {
                        Some('\'') => break,
                        Some(c) => w.push(c),
                        None => return Err(format!("unbalanced ' in `{cmd}`")),
                    }
                }
            }
            '"' => {
                let w = word.get_or_insert_with(String::new);
                loop {
                    match chars.next() {
                        Some('"') => break,
                        Some('\\') => match chars.next() {
                            Some(c @ ('"' | '\\' | '$' | '`')) => w.push(c),
                            Some(c) => w.extend(['\\', c]),
                            None => return Err(format!("unbalanced \" in `{cmd}`")),
                        },
                        Some(c) => w.push(c),
                        None => return Err(format!("unbalanced \" in `{cmd}`")),
                    }
                }
            }
            '\\' => word.get_or_insert_with(String::new).extend(chars.next()),
            c => word.get_or_insert_with(String::new).push(c),
        }
    }
    words.extend(word);
    if words.is_empty() {
        return Err("the command is empty".into());
    }
    Ok(words)
}

/// Whether `program` can be started: a path to an executable file, or a name found on PATH.
pub fn find_program(program: &str) -> Option<PathBuf> {
    use std::os::unix::fs::PermissionsExt;
    let runnable = |p: &Path| std::fs::metadata(p).is_ok_and(|m| m.is_file() && m.permissions().mode() & 0o111 != 0);
    if program.contains('/') {
        return runnable(Path::new(program)).then(|| program.into());
    }
    let path = std::env::var_os("PATH")?;
    std::env::split_paths(&path).map(|dir| dir.join(program)).find(|p| runnable(p))
}

/// A user's command (`--controller-cmd`, `--plant-cmd`) split into words, refused up front, naming `flag`, when it
/// does not split or its program cannot be found.
pub fn check_command(flag: &str, cmd: &str) -> Result<Vec<String>, String> {
    let words = split_command(cmd).map_err(|e| format!("--{flag}: {e}"))?;
    if find_program(&words[0]).is_none() {
        return Err(format!("--{flag}: cannot find `{}` (not an executable file, and not on PATH)", words[0]));
    }
    Ok(words)
}

/// `text` as one word of a POSIX shell command: as is when it is plain, else single-quoted (the commands a check
/// or a sweep prints to fly a case again).
pub fn shell_quote(text: &str) -> String {
    if !text.is_empty() && text.chars().all(|c| c.is_ascii_alphanumeric() || "-_./=:@".contains(c)) {
        text.to_string()
    } else {
        format!("'{}'", text.replace('\'', "'\\''"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn controller_commands_split_like_a_shell() {
        let words = |c: &str| split_command(c).unwrap();
        assert_eq!(words("python3 examples/python/pd.py"), ["python3", "examples/python/pd.py"]);
        assert_eq!(
            words("  ./ctl  --gain 'a b'  \"c \\\" d\" e\\ f ''"),
            ["./ctl", "--gain", "a b", "c \" d", "e f", ""]
        );
        assert_eq!(words(r#"say "a\nb""#), ["say", "a\\nb"]);
        assert!(split_command("   ").unwrap_err().contains("empty"));
        assert!(split_command("ctl 'oops").unwrap_err().contains("unbalanced '"));
        assert!(split_command("ctl \"oops").unwrap_err().contains("unbalanced \""));
    }

    #[test]
    fn programs_are_found_on_path_or_by_path() {
        assert!(find_program("sh").is_some());
        assert!(find_program("/bin/sh").is_some());
        assert!(find_program("surely-no-such-program-here").is_none());
        assert!(find_program("./no/such/file").is_none());
    }
}
