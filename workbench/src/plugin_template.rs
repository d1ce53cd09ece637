//! The crate `flarebench plugins new` writes: the plugin guide's example crate
//! (`algorithms/example-glow`, compiled into the binary from its own files, so the two cannot
//! differ) with its package, library and plugin names replaced, made a crate of its own that
//! depends on the sdk by path.

use std::path::Path;

use anyhow::{bail, ensure};

/// The example crate's manifest and code (docs/plugins.md shows both verbatim).
const EXAMPLE_CARGO_TOML: &str = include_str!("../../algorithms/example-glow/Cargo.toml");
const EXAMPLE_LIB_RS: &str = include_str!("../../algorithms/example-glow/src/lib.rs");
/// The workspace manifest, for the values the example inherits from it.
const WORKSPACE_CARGO_TOML: &str = include_str!("../../Cargo.toml");

/// Most bytes in a plugin name (the host's limit, `sdk::abi::host`).
const MAX_NAME_LEN: usize = 64;

/// Rust's keywords, strict and reserved, and the crate names cargo keeps for the standard
/// library: none can be a library's name.
const RESERVED: &[&str] = &[
    "abstract",
    "alloc",
    "as",
    "async",
    "await",
    "become",
    "box",
    "break",
    "const",
    "continue",
    "core",
    "crate",
    "do",
    "dyn",
    "else",
    "enum",
    "extern",
    "false",
    "final",
    "fn",
    "for",
    "gen",
    "if",
    "impl",
    "in",
    "let",
    "loop",
    "macro",
    "match",
    "mod",
    "move",
    "mut",
    "override",
    "priv",
    "proc_macro",
    "pub",
    "ref",
    "return",
    "self",
    "static",
    "std",
    "struct",
    "super",
    "test",
    "trait",
    "true",
    "try",
    "type",
    "typeof",
    "unsafe",
    "unsized",
    "use",
    "virtual",
    "where",
    "while",
    "yield",
];

/// The files of a new plugin crate.
#[derive(Debug, Clone, PartialEq)]
pub struct PluginCrate {
    /// The plugin's name: the package's name and the name `plugins list` shows.
    pub name: String,
    /// The library's name: the plugin name with `-` as `_` (the file is `lib{lib_name}.so`).
    pub lib_name: String,
    pub cargo_toml: String,
    pub lib_rs: String,
    pub gitignore: String,
}

/// Checks that `name` can be a plugin's name, a package's name and (with `-` as `_`) a
/// library's name, and that discovery will not skip it.
pub fn check_name(name: &str) -> anyhow::Result<()> {
    ensure!(!name.is_empty(), "the plugin name is empty");
    ensure!(
        name.len() <= MAX_NAME_LEN,
        "the plugin name `{name}` is {} bytes long; the host takes at most {MAX_NAME_LEN}",
        name.len()
    );
    if let Some(c) = name
        .chars()
        .find(|c| !(c.is_ascii_alphanumeric() || *c == '-' || *c == '_'))
    {
        bail!(
            "the plugin name `{name}` has `{c}`: use ASCII letters, digits, `-` and `_` \
             (it is the crate's name too)"
        );
    }
    ensure!(
        name.starts_with(|c: char| c.is_ascii_alphabetic()),
        "the plugin name `{name}` must start with a letter (it names the crate's library)"
    );
    let lib = lib_name(name);
    ensure!(
        !RESERVED.contains(&lib.as_str()),
        "`{name}` is a Rust keyword or a standard library crate's name, so it cannot name a library; choose another name"
    );
    ensure!(
        !lib.starts_with(crate::plugin_dirs::TEST_PLUGIN_PREFIX),
        "a library named `{}…` is taken for the workbench's test plugins and skipped when plugins are searched for; choose another name",
        crate::plugin_dirs::TEST_PLUGIN_PREFIX
    );
    Ok(())
}

/// The library name of plugin `name`: `-` becomes `_`.
pub fn lib_name(name: &str) -> String {
    name.replace('-', "_")
}

/// `text` with `from` (which it holds exactly once) replaced by `to`.
fn replace_once(text: &str, from: &str, to: &str, file: &str) -> String {
    assert_eq!(
        text.matches(from).count(),
        1,
        "the example crate's {file} holds `{from}` exactly once (plugin_template's tests check it)"
    );
    text.replacen(from, to, 1)
}

/// The value of `key` in the workspace manifest's `[workspace.package]` table.
fn workspace_package(key: &str) -> &'static str {
    let table = WORKSPACE_CARGO_TOML
        .split("[workspace.package]")
        .nth(1)
        .expect("the workspace manifest has a [workspace.package] table");
    table
        .lines()
        .take_while(|l| !l.starts_with('['))
        .find_map(|l| {
            let (k, v) = l.split_once('=')?;
            (k.trim() == key).then(|| v.trim().trim_matches('"'))
        })
        .unwrap_or_else(|| {
            panic!("[workspace.package] sets `{key}` (plugin_template's tests check it)")
        })
}

/// A TOML basic string holding `s`.
fn toml_string(s: &str) -> String {
    let mut out = String::from("\"");
    for c in s.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            c if c.is_control() => out.push_str(&format!("\\u{:04X}", c as u32)),
            c => out.push(c),
        }
    }
    out.push('"');
    out
}

/// The crate of plugin `name` (checked by [`check_name`]) depending on the sdk at `sdk` (the
/// directory of its `Cargo.toml`).
pub fn plugin_crate(name: &str, sdk: &Path) -> PluginCrate {
    let lib = lib_name(name);
    let file = "Cargo.toml";
    let mut toml = EXAMPLE_CARGO_TOML.to_string();
    for (from, to) in [
        (
            "name = \"flarebench-example-glow\"".to_string(),
            format!("name = \"{name}\""),
        ),
        (
            toml_line("description", EXAMPLE_CARGO_TOML),
            format!(
                "description = \"flarebench plugin {name}: a soft glow at each light's image (from the example of flarebench's docs/plugins.md)\""
            ),
        ),
        (
            "rust-version.workspace = true".into(),
            format!("rust-version = \"{}\"", workspace_package("rust-version")),
        ),
        (
            "\nversion.workspace = true".into(),
            "\nversion = \"0.1.0\"".into(),
        ),
        (
            "edition.workspace = true".into(),
            format!("edition = \"{}\"", workspace_package("edition")),
        ),
        // The licence is the author's choice.
        ("license.workspace = true\n".into(), String::new()),
        (
            "name = \"example_glow\"".into(),
            format!("name = \"{lib}\""),
        ),
        (
            "flarebench-sdk.workspace = true".into(),
            format!(
                "flarebench-sdk = {{ path = {} }}",
                toml_string(&sdk.to_string_lossy())
            ),
        ),
        // The workspace's lints are not the new crate's.
        ("\n[lints]\nworkspace = true\n".into(), "\n".into()),
    ] {
        toml = replace_once(&toml, &from, &to, file);
    }
    toml.push_str(
        "# A workspace of its own: cargo builds the crate wherever it lies, inside another\n\
         # workspace too (to make it a member of one instead, remove this table and add the\n\
         # crate to that workspace's `members`).\n\
         [workspace]\n\
         \n\
         # The sdk and the other dependencies optimised in debug builds too, as in flarebench's\n\
         # own workspace: unoptimised, the sdk's tracer is many times slower.\n\
         [profile.dev.package.\"*\"]\n\
         opt-level = 2\n",
    );

    let file = "src/lib.rs";
    let mut code = EXAMPLE_LIB_RS.to_string();
    for (from, to) in [
        (
            "//! The example plugin of `docs/plugins.md`: ".to_string(),
            format!(
                "//! The flarebench plugin `{name}`, made by `flarebench plugins new` from the example of\n//! flarebench's `docs/plugins.md`: "
            ),
        ),
        (
            "name: \"example-glow\",".into(),
            format!("name: \"{name}\","),
        ),
        (
            "(the plugin guide's example)".into(),
            "(from the plugin guide's example)".into(),
        ),
    ] {
        code = replace_once(&code, &from, &to, file);
    }
    PluginCrate {
        name: name.to_string(),
        lib_name: lib,
        cargo_toml: toml,
        lib_rs: code,
        gitignore: "/target\n".into(),
    }
}

/// The whole line of `text` that sets `key` (without its newline).
fn toml_line(key: &str, text: &str) -> String {
    text.lines()
        .find(|l| l.split_once('=').is_some_and(|(k, _)| k.trim() == key))
        .unwrap_or_else(|| panic!("the example crate's Cargo.toml sets `{key}`"))
        .to_string()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_replacement_applies_and_no_example_name_is_left() {
        let c = plugin_crate("my-glow", Path::new("/opt/flare bench/sdk"));
        assert_eq!(c.lib_name, "my_glow");
        assert!(
            c.cargo_toml.contains("name = \"my-glow\""),
            "{}",
            c.cargo_toml
        );
        assert!(
            c.cargo_toml.contains("name = \"my_glow\""),
            "{}",
            c.cargo_toml
        );
        assert!(
            c.cargo_toml
                .contains("flarebench-sdk = { path = \"/opt/flare bench/sdk\" }"),
            "{}",
            c.cargo_toml
        );
        assert!(c.cargo_toml.contains("\n[workspace]\n"));
        let edition = format!("edition = \"{}\"", workspace_package("edition"));
        assert!(c.cargo_toml.contains(&edition), "{}", c.cargo_toml);
        assert!(!c.cargo_toml.contains(".workspace"), "{}", c.cargo_toml);
        assert!(!c.cargo_toml.contains("[lints]"), "{}", c.cargo_toml);
        assert!(c.lib_rs.contains("name: \"my-glow\","));
        for text in [&c.cargo_toml, &c.lib_rs] {
            assert!(!text.contains("example-glow"), "{text}");
            assert!(!text.contains("example_glow"), "{text}");
        }
        // Only the names changed: the code is the example's, line for line after the header.
        let tail = |s: &str| s.split_once("\nuse ").map(|(_, t)| t.to_string());
        assert_eq!(
            tail(&c.lib_rs).map(|t| t.replace("my-glow", "example-glow")),
            tail(EXAMPLE_LIB_RS).map(|t| t.replace(
                "(the plugin guide's example)",
                "(from the plugin guide's example)"
            ))
        );
    }

    #[test]
    fn a_windows_sdk_path_is_written_as_a_toml_string() {
        let c = plugin_crate("g", Path::new(r#"C:\src\flare"bench\sdk"#));
        assert!(
            c.cargo_toml
                .contains(r#"flarebench-sdk = { path = "C:\\src\\flare\"bench\\sdk" }"#),
            "{}",
            c.cargo_toml
        );
    }

    #[test]
    fn names_that_cannot_name_a_crate_or_would_be_skipped_are_refused() {
        for ok in ["glow", "my-glow", "ghost_v2", "A1"] {
            assert!(check_name(ok).is_ok(), "{ok}");
        }
        for (bad, says) in [
            ("", "empty"),
            ("9lives", "start with a letter"),
            ("-x", "start with a letter"),
            ("my glow", "has ` `"),
            ("glow.v2", "has `.`"),
            ("düse", "has `ü`"),
            ("fn", "keyword"),
            ("test", "keyword"),
            ("flarebench-test-x", "test plugins"),
        ] {
            let e = check_name(bad).expect_err(bad).to_string();
            assert!(e.contains(says), "{bad}: {e}");
        }
        let long = "g".repeat(MAX_NAME_LEN + 1);
        assert!(
            check_name(&long)
                .unwrap_err()
                .to_string()
                .contains("at most")
        );
    }
}
