//! No import cycles between the files of a crate (issue 32 item 4).
//!
//! Scans the `src/` tree of every workspace crate and builds, per crate, a graph with one node per source file and an edge `a → b`
//! when file `a` names an item defined in file `b`: `use crate::…`, `use super::…`,
//! `use self::…`, a child module's name (`use child::X`, `child::f()`) and the same paths in
//! expressions and types. Re-exports (`pub use x::Y;`) are aliases, not uses: a path through
//! a re-export is followed to the file that defines the item. `mod x;` declarations are not
//! edges, nor are comments, doc links or string literals, nor test code (`#[cfg(test)]`
//! modules, inline or in files: tests may use any layer). A strongly connected component of
//! two or more files is a cycle and fails the test, listing one edge of each file with its
//! line.
//!
//! The scanner is lexical (no macro expansion, no `#[path]`): it errs towards missing an edge
//! hidden in a macro, never towards inventing one.

use std::collections::{BTreeMap, BTreeSet};
use std::fs;
use std::path::{Path, PathBuf};

/// Crates the scan leaves out (owned and checked elsewhere).
const SKIPPED: &[&str] = &[];

/// Cycles known when the check was written, in files other helpers were editing at the time
/// (issue 32 item 4): each is a crate and the files of one cycle. The test fails on any other
/// cycle, and on a listed one that has gone (so the list only shrinks). Remove an entry when
/// its cycle is broken.
const KNOWN: &[(&str, &[&str])] = &[
    (
        "crates/brdf",
        &[
            "analytic.rs",
            "brdf.rs",
            "measured/cornell.rs",
            "measured/rgl.rs",
            "merl.rs",
            "registry.rs",
        ],
    ),
    (
        "crates/envmap",
        &["load/exr.rs", "load/hdr.rs", "load/mod.rs", "load/pfm.rs"],
    ),
];

fn workspace_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// The `src/` directories of the workspace's crates (members of the root manifest).
fn crate_sources(root: &Path) -> Vec<(String, PathBuf)> {
    let manifest = fs::read_to_string(root.join("Cargo.toml")).expect("root Cargo.toml");
    let members = manifest
        .split("members")
        .nth(1)
        .and_then(|s| s.split(']').next())
        .expect("workspace members");
    members
        .split('"')
        .skip(1)
        .step_by(2)
        .filter(|m| !SKIPPED.contains(m))
        .map(|m| (m.to_string(), root.join(m).join("src")))
        .filter(|(_, src)| src.is_dir())
        .collect()
}

/// Source with comments, string and char literals blanked (line breaks kept).
fn strip(src: &str) -> String {
    let b: Vec<char> = src.chars().collect();
    let mut out = String::with_capacity(src.len());
    let blank = |out: &mut String, c: char| out.push(if c == '\n' { '\n' } else { ' ' });
    let mut i = 0;
    while i < b.len() {
        let c = b[i];
        let next = b.get(i + 1).copied();
        if c == '/' && next == Some('/') {
            while i < b.len() && b[i] != '\n' {
                i += 1;
            }
        } else if c == '/' && next == Some('*') {
            let mut depth = 0;
            while i < b.len() {
                if b[i] == '/' && b.get(i + 1) == Some(&'*') {
                    depth += 1;
                    i += 2;
                    out.push_str("  ");
                } else if b[i] == '*' && b.get(i + 1) == Some(&'/') {
                    depth -= 1;
                    i += 2;
                    out.push_str("  ");
                    if depth == 0 {
                        break;
                    }
                } else {
                    blank(&mut out, b[i]);
                    i += 1;
                }
            }
        } else if (c == 'r' || c == 'b')
            && !b
                .get(i.wrapping_sub(1))
                .is_some_and(|p| p.is_alphanumeric() || *p == '_')
            && raw_string_start(&b, i).is_some()
        {
            let (hashes, body) = raw_string_start(&b, i).expect("checked");
            for &ch in &b[i..body] {
                blank(&mut out, ch);
            }
            i = body;
            loop {
                if i >= b.len() {
                    break;
                }
                if b[i] == '"' && (0..hashes).all(|k| b.get(i + 1 + k) == Some(&'#')) {
                    for _ in 0..=hashes {
                        out.push(' ');
                    }
                    i += 1 + hashes;
                    break;
                }
                blank(&mut out, b[i]);
                i += 1;
            }
        } else if c == '"' {
            out.push(' ');
            i += 1;
            while i < b.len() && b[i] != '"' {
                if b[i] == '\\' {
                    blank(&mut out, b[i]);
                    i += 1;
                }
                if i < b.len() {
                    blank(&mut out, b[i]);
                    i += 1;
                }
            }
            out.push(' ');
            i += 1;
        } else if c == '\'' {
            // A char literal ('x', '\n', '\u{..}') or a lifetime ('a).
            let end = if next == Some('\\') {
                (i + 2..b.len()).find(|&k| b[k] == '\'')
            } else if b.get(i + 2) == Some(&'\'') {
                Some(i + 2)
            } else {
                None
            };
            match end {
                Some(e) => {
                    for &ch in &b[i..=e] {
                        blank(&mut out, ch);
                    }
                    i = e + 1;
                }
                None => {
                    out.push(c);
                    i += 1;
                }
            }
        } else {
            out.push(c);
            i += 1;
        }
    }
    out
}

/// If a raw (byte) string starts at `i`: its number of `#` and the index of its body.
fn raw_string_start(b: &[char], i: usize) -> Option<(usize, usize)> {
    let mut k = i;
    if b[k] == 'b' {
        k += 1;
    }
    if b.get(k) != Some(&'r') {
        return None;
    }
    k += 1;
    let mut hashes = 0;
    while b.get(k) == Some(&'#') {
        hashes += 1;
        k += 1;
    }
    (b.get(k) == Some(&'"')).then_some((hashes, k + 1))
}

/// One source file of a crate.
struct SrcFile {
    rel: String,
    module: Vec<String>,
    text: String,
}

fn collect_files(dir: &Path, src: &Path, out: &mut Vec<SrcFile>) {
    let mut entries: Vec<_> = fs::read_dir(dir)
        .expect("read src dir")
        .map(|e| e.expect("dir entry").path())
        .collect();
    entries.sort();
    for path in entries {
        if path.is_dir() {
            collect_files(&path, src, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            let rel = path.strip_prefix(src).expect("under src");
            let mut module: Vec<String> = rel
                .with_extension("")
                .components()
                .map(|c| c.as_os_str().to_string_lossy().into_owned())
                .collect();
            let last = module.last().cloned().unwrap_or_default();
            if module.len() == 1 && ["lib", "main"].contains(&last.as_str()) {
                module.clear();
            } else if last == "mod" {
                module.pop();
            }
            let text = strip(&fs::read_to_string(&path).expect("read source"));
            out.push(SrcFile {
                rel: rel.to_string_lossy().into_owned(),
                module,
                text,
            });
        }
    }
}

fn is_ident(c: char) -> bool {
    c.is_alphanumeric() || c == '_'
}

/// Expands a use tree (`a::{b, c::{d, e as f}}`) into paths; `self` in braces names the prefix.
fn expand_use(tree: &str, prefix: &[String], out: &mut Vec<Vec<String>>) {
    let tree = tree.trim();
    if tree.is_empty() {
        return;
    }
    if let Some(open) = tree.find('{') {
        let head: Vec<String> = tree[..open]
            .split("::")
            .map(str::trim)
            .filter(|s| !s.is_empty())
            .map(String::from)
            .collect();
        let mut base = prefix.to_vec();
        base.extend(head);
        let inner = &tree[open + 1..tree.rfind('}').unwrap_or(tree.len())];
        let mut depth = 0;
        let mut start = 0;
        for (k, ch) in inner.char_indices() {
            match ch {
                '{' => depth += 1,
                '}' => depth -= 1,
                ',' if depth == 0 => {
                    expand_use(&inner[start..k], &base, out);
                    start = k + 1;
                }
                _ => {}
            }
        }
        expand_use(&inner[start..], &base, out);
    } else {
        let item = tree.split(" as ").next().unwrap_or(tree);
        let mut path = prefix.to_vec();
        for seg in item.split("::").map(str::trim).filter(|s| !s.is_empty()) {
            if seg == "self" && !path.is_empty() {
                continue;
            }
            path.push(seg.to_string());
        }
        out.push(path);
    }
}

/// A path named in a file, with the module it is named from and its line.
struct Named {
    from: Vec<String>,
    path: Vec<String>,
    line: usize,
    reexport: bool,
    test: bool,
}

/// Whether the item starting at byte `pos` carries `#[cfg(test)]` among its attributes.
fn cfg_test_before(text: &str, pos: usize) -> bool {
    let before = &text[..pos];
    let start = before.rfind([';', '}', '{']).map_or(0, |p| p + 1);
    before[start..].contains("#[cfg(test)]")
}

/// Inline module stack of each byte (`mod tests { … }`) and the paths a file names.
fn scan(file: &SrcFile, children: &BTreeMap<Vec<String>, BTreeSet<String>>) -> Vec<Named> {
    let text = &file.text;
    let chars: Vec<(usize, char)> = text.char_indices().collect();
    let mut named = Vec::new();
    // Inline modules open at this point: name, brace depth, under `#[cfg(test)]`.
    let mut stack: Vec<(String, i32, bool)> = Vec::new();
    let mut depth = 0i32;
    let mut line = 1;
    let mut k = 0;
    let word_at = |k: usize| -> &str {
        let start = chars[k].0;
        let end = chars[k..]
            .iter()
            .find(|(_, c)| !is_ident(*c))
            .map_or(text.len(), |(p, _)| *p);
        &text[start..end]
    };
    while k < chars.len() {
        let (pos, c) = chars[k];
        let prev = if k == 0 { ' ' } else { chars[k - 1].1 };
        match c {
            '\n' => line += 1,
            '{' => depth += 1,
            '}' => {
                depth -= 1;
                if stack.last().is_some_and(|(_, d, _)| *d == depth) {
                    stack.pop();
                }
            }
            _ => {}
        }
        let mut module = file.module.clone();
        module.extend(stack.iter().map(|(m, _, _)| m.clone()));
        let test = stack.iter().any(|(_, _, t)| *t);
        if is_ident(c) && !is_ident(prev) {
            let word = word_at(k);
            let before = text[..pos].trim_end();
            let after_colons = before.ends_with("::");
            if word == "mod" {
                let rest = &text[pos + 3..];
                let name: String = rest
                    .trim_start()
                    .chars()
                    .take_while(|c| is_ident(*c))
                    .collect();
                let tail = rest.trim_start()[name.len()..].trim_start();
                if tail.starts_with('{') {
                    stack.push((name, depth, cfg_test_before(text, pos)));
                }
            } else if word == "use" {
                let end = text[pos..].find(';').map_or(text.len(), |e| pos + e);
                let reexport = before.ends_with("pub") || before.ends_with(')');
                let mut paths = Vec::new();
                expand_use(&text[pos + 3..end], &[], &mut paths);
                for path in paths {
                    named.push(Named {
                        from: module.clone(),
                        path,
                        line,
                        reexport,
                        test,
                    });
                }
                line += text[pos..end].matches('\n').count();
                while k < chars.len() && chars[k].0 < end {
                    k += 1;
                }
                continue;
            } else if !after_colons && text[pos + word.len()..].starts_with("::") {
                let kids = children.get(&module);
                let relative = ["crate", "super", "self"].contains(&word)
                    || kids.is_some_and(|kids| kids.contains(word));
                if relative {
                    let end = text[pos..]
                        .find(|ch: char| !(is_ident(ch) || ch == ':'))
                        .map_or(text.len(), |e| pos + e);
                    let path: Vec<String> = text[pos..end]
                        .split("::")
                        .filter(|s| !s.is_empty())
                        .map(String::from)
                        .collect();
                    named.push(Named {
                        from: module.clone(),
                        path,
                        line,
                        reexport: false,
                        test,
                    });
                }
            }
            k += word.chars().count();
            continue;
        }
        k += 1;
    }
    named
}

/// Absolute module path of `path` named from module `from` (`None`: outside the crate).
fn absolute(
    from: &[String],
    path: &[String],
    children: &BTreeMap<Vec<String>, BTreeSet<String>>,
) -> Option<Vec<String>> {
    let first = path.first()?;
    let mut base: Vec<String> = match first.as_str() {
        "crate" => Vec::new(),
        "self" => from.to_vec(),
        "super" => from.to_vec(),
        _ if children.get(from).is_some_and(|kids| kids.contains(first)) => from.to_vec(),
        _ => return None,
    };
    let mut rest = if first == "crate" || first == "self" {
        &path[1..]
    } else {
        path
    };
    while rest.first().is_some_and(|s| s == "super") {
        base.pop()?;
        rest = &rest[1..];
    }
    base.extend(rest.iter().cloned());
    Some(base)
}

/// Per crate: file of each module path and re-exports (module path of alias → target path).
struct Crate {
    files: Vec<SrcFile>,
    file_of: BTreeMap<Vec<String>, usize>,
    children: BTreeMap<Vec<String>, BTreeSet<String>>,
    reexports: BTreeMap<Vec<String>, Vec<String>>,
    /// Module files declared under `#[cfg(test)]` (`#[cfg(test)] mod x;`).
    test_only: BTreeSet<Vec<String>>,
}

impl Crate {
    fn load(src: &Path) -> Crate {
        let mut files = Vec::new();
        collect_files(src, src, &mut files);
        // src/bin/* are crate roots of their own, and so is main.rs beside a lib.rs: the scan
        // reads the library's module tree (or main.rs's when there is no library).
        let has_lib = files.iter().any(|f| f.rel == "lib.rs");
        files.retain(|f| !(f.rel.starts_with("bin/") || (has_lib && f.rel == "main.rs")));
        let mut file_of = BTreeMap::new();
        let mut children: BTreeMap<Vec<String>, BTreeSet<String>> = BTreeMap::new();
        for (i, f) in files.iter().enumerate() {
            file_of.insert(f.module.clone(), i);
            if let Some((last, parent)) = f.module.split_last() {
                children
                    .entry(parent.to_vec())
                    .or_default()
                    .insert(last.clone());
            }
        }
        // Inline modules are children too (found lexically: `mod name {`); file modules
        // declared under `#[cfg(test)]` are test code.
        let mut test_only = BTreeSet::new();
        for f in &files {
            for (pos, _) in f.text.match_indices("mod ") {
                if pos > 0 && f.text[..pos].ends_with(is_ident) {
                    continue;
                }
                let rest = &f.text[pos + 4..];
                let name: String = rest.chars().take_while(|c| is_ident(*c)).collect();
                let tail = rest[name.len()..].trim_start();
                if tail.starts_with('{') {
                    children.entry(f.module.clone()).or_default().insert(name);
                } else if tail.starts_with(';') && cfg_test_before(&f.text, pos) {
                    let mut module = f.module.clone();
                    module.push(name);
                    test_only.insert(module);
                }
            }
        }
        let mut krate = Crate {
            files,
            file_of,
            children,
            reexports: BTreeMap::new(),
            test_only,
        };
        let mut reexports = BTreeMap::new();
        for f in &krate.files {
            for n in scan(f, &krate.children) {
                if !n.reexport {
                    continue;
                }
                if let (Some(target), Some(name)) =
                    (absolute(&n.from, &n.path, &krate.children), n.path.last())
                {
                    if name == "*" {
                        continue;
                    }
                    let mut alias = n.from.clone();
                    alias.push(name.clone());
                    if alias != target {
                        reexports.insert(alias, target);
                    }
                }
            }
        }
        krate.reexports = reexports;
        krate
    }

    /// File that defines the item at module path `path`, following re-exports.
    fn defining_file(&self, path: &[String]) -> Option<usize> {
        let mut path = path.to_vec();
        for _ in 0..16 {
            if path.last().is_some_and(|s| s == "*") {
                path.pop();
            }
            // Longest prefix that is a re-export alias: substitute and retry.
            let alias = (1..=path.len())
                .rev()
                .find(|&n| self.reexports.contains_key(&path[..n]));
            if let Some(n) = alias {
                let mut next = self.reexports[&path[..n]].clone();
                next.extend(path[n..].iter().cloned());
                if next == path {
                    break;
                }
                path = next;
                continue;
            }
            break;
        }
        (0..=path.len())
            .rev()
            .find_map(|n| self.file_of.get(&path[..n]).copied())
    }

    /// Edges between files: `(from, to) → first line of `from` naming `to``.
    fn edges(&self) -> BTreeMap<(usize, usize), usize> {
        let mut edges = BTreeMap::new();
        for (i, f) in self.files.iter().enumerate() {
            let test_file = (0..=f.module.len()).any(|n| self.test_only.contains(&f.module[..n]));
            if test_file {
                continue;
            }
            for n in scan(f, &self.children) {
                if n.reexport || n.test {
                    continue;
                }
                let Some(target) = absolute(&n.from, &n.path, &self.children) else {
                    continue;
                };
                if let Some(j) = self.defining_file(&target)
                    && j != i
                {
                    edges.entry((i, j)).or_insert(n.line);
                }
            }
        }
        edges
    }
}

/// Strongly connected components of two or more nodes (Tarjan).
fn cycles(n: usize, edges: &BTreeMap<(usize, usize), usize>) -> Vec<Vec<usize>> {
    struct State {
        index: Vec<Option<usize>>,
        low: Vec<usize>,
        on_stack: Vec<bool>,
        stack: Vec<usize>,
        next: usize,
        out: Vec<Vec<usize>>,
    }
    fn visit(v: usize, adj: &[Vec<usize>], s: &mut State) {
        s.index[v] = Some(s.next);
        s.low[v] = s.next;
        s.next += 1;
        s.stack.push(v);
        s.on_stack[v] = true;
        for &w in &adj[v] {
            match s.index[w] {
                None => {
                    visit(w, adj, s);
                    s.low[v] = s.low[v].min(s.low[w]);
                }
                Some(iw) if s.on_stack[w] => s.low[v] = s.low[v].min(iw),
                _ => {}
            }
        }
        if Some(s.low[v]) == s.index[v] {
            let mut comp = Vec::new();
            while let Some(w) = s.stack.pop() {
                s.on_stack[w] = false;
                comp.push(w);
                if w == v {
                    break;
                }
            }
            if comp.len() > 1 {
                comp.sort();
                s.out.push(comp);
            }
        }
    }
    let mut adj = vec![Vec::new(); n];
    for &(a, b) in edges.keys() {
        adj[a].push(b);
    }
    let mut s = State {
        index: vec![None; n],
        low: vec![0; n],
        on_stack: vec![false; n],
        stack: Vec::new(),
        next: 0,
        out: Vec::new(),
    };
    for v in 0..n {
        if s.index[v].is_none() {
            visit(v, &adj, &mut s);
        }
    }
    s.out
}

/// Every cycle of the workspace: the crate, its files, and one line per edge inside it
/// (`file:line → file`).
fn workspace_cycles(root: &Path) -> Vec<(String, Vec<String>, String)> {
    let mut report = Vec::new();
    for (name, src) in crate_sources(root) {
        let krate = Crate::load(&src);
        let edges = krate.edges();
        for comp in cycles(krate.files.len(), &edges) {
            let members: BTreeSet<usize> = comp.iter().copied().collect();
            let mut lines = vec![format!("cycle in {name}:")];
            for &a in &comp {
                for (&(from, to), line) in &edges {
                    if from == a && members.contains(&to) {
                        lines.push(format!(
                            "  src/{}:{line} → src/{}",
                            krate.files[from].rel, krate.files[to].rel
                        ));
                    }
                }
            }
            let files = comp.iter().map(|&i| krate.files[i].rel.clone()).collect();
            report.push((name.clone(), files, lines.join("\n")));
        }
    }
    report
}

#[test]
fn no_import_cycles_between_files_of_a_crate() {
    let root = workspace_root();
    let crates = crate_sources(&root);
    assert!(
        crates.len() >= 10,
        "found only {} crates under {}",
        crates.len(),
        root.display()
    );
    let found = workspace_cycles(&root);
    let is_known = |name: &str, files: &[String]| {
        KNOWN
            .iter()
            .any(|(krate, known)| *krate == name && known.iter().eq(files.iter()))
    };
    let new: Vec<&str> = found
        .iter()
        .filter(|(name, files, _)| !is_known(name, files))
        .map(|(_, _, lines)| lines.as_str())
        .collect();
    assert!(new.is_empty(), "import cycles:\n{}", new.join("\n"));
    let gone: Vec<String> = KNOWN
        .iter()
        .filter(|(krate, known)| {
            !found
                .iter()
                .any(|(name, files, _)| name == krate && known.iter().eq(files.iter()))
        })
        .map(|(krate, known)| format!("{krate}: {known:?}"))
        .collect();
    assert!(
        gone.is_empty(),
        "known cycles no longer found (remove them from KNOWN):\n{}",
        gone.join("\n")
    );
}

#[test]
fn the_scanner_finds_a_planted_cycle_and_follows_re_exports() {
    let dir = std::env::temp_dir().join(format!("import-cycles-{}", std::process::id()));
    let src = dir.join("src");
    fs::create_dir_all(src.join("inner")).expect("mkdir");
    let write = |rel: &str, text: &str| fs::write(src.join(rel), text).expect("write");
    write(
        "lib.rs",
        "mod a;\nmod b;\nmod inner;\n#[cfg(test)]\nmod checks;\npub use a::A;\npub use b::B;\n",
    );
    // Test code names any layer without an edge: a `#[cfg(test)]` file and an inline module.
    write("checks.rs", "use crate::inner::Z;\nuse crate::a::A;\n");
    // a → b through the crate root's re-export; b → a through `super`.
    write(
        "a.rs",
        "//! use crate::inner::Z;\npub struct A(crate::B);\n",
    );
    write(
        "b.rs",
        "pub struct B;\nfn f() -> &'static str { \"crate::inner::Z\" }\nfn g(_: super::a::A) {}\n",
    );
    // inner/mod.rs uses its child; the child names nothing: no cycle.
    write(
        "inner/mod.rs",
        "mod leaf;\npub use leaf::Z;\nfn h(_: leaf::Z) {}\n",
    );
    write(
        "inner/leaf.rs",
        "pub struct Z;\n#[cfg(test)]\nmod tests {\n    use crate::a::A;\n}\n",
    );
    let krate = Crate::load(&src);
    let edges = krate.edges();
    let name = |i: usize| krate.files[i].rel.clone();
    let named: BTreeSet<(String, String)> =
        edges.keys().map(|&(a, b)| (name(a), name(b))).collect();
    let expected: BTreeSet<(String, String)> = [
        ("a.rs", "b.rs"),
        ("b.rs", "a.rs"),
        ("inner/mod.rs", "inner/leaf.rs"),
    ]
    .iter()
    .map(|(a, b)| (a.to_string(), b.to_string()))
    .collect();
    assert_eq!(named, expected);
    let found = cycles(krate.files.len(), &edges);
    assert_eq!(found.len(), 1);
    let files: Vec<String> = found[0].iter().map(|&i| name(i)).collect();
    assert_eq!(files, ["a.rs", "b.rs"]);
    fs::remove_dir_all(&dir).expect("remove temp dir");
}
