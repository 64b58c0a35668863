//! Developer workflows (`cargo xtask …`): reproduce the paper, summarise the benchmarks, check the
//! dependency direction between the crates.

use std::path::{Path, PathBuf};
use std::process::Command;

use anyhow::{Context, Result, bail};

mod bench;
mod real_data;

const HELP: &str = "\
cargo xtask <task>

Tasks:
  reproduce-paper [--check]   Rerun the paper's case studies (Tables 13-18) with the bundled IRB 140 and
                              write the report and plots into target/paper-reproduction/ (never over a
                              tracked file); with --check, compare with
                              fixtures/golden/paper-reproduction.json and fail on drift.
  bless-golden                Regenerate the committed docs/paper-reproduction.md, docs/img/*.svg and
                              fixtures/golden/paper-reproduction.json from a fresh run.
  bench [--json] [--baseline COMMIT]
                              Run the criterion benches and print a summary table (the last line is one
                              JSON object with --json), then the diagnosis's cost phase by phase on the
                              real UR10 sets (C with B held out; the week of series A). With --baseline,
                              COMMIT's command line is built in a worktree under target/baseline/ and
                              both builds run the real sets one after the other: CPU, wall, peak memory
                              and figures side by side, with the CPU ratio.
  real-data                   Rerun every shared real set (UR10 C -> B, series A, WAM, Rokae) with the
                              release build, in both protocols where there is a hold-out file, and write
                              one table (figures, time, memory, processor, date) to docs/real-data.md.
  measure BIN ARGS...         (used by bench --baseline and real-data) Run one command and print its CPU
                              seconds, wall seconds and peak memory as JSON.
  wheel                       Build the Python package's one abi3 wheel into target/wheels/ (maturin,
                              `pip install maturin`): it installs on any CPython >= 3.9 of this platform
                              with no Rust toolchain.
  package                     `cargo package` every workspace member not marked `publish = false` (the
                              library crates), each verified by building it from its packaged sources.
  deps                        Check that dependencies point one way (the core never depends on I/O,
                              the CLI or file formats).
  tidy                        Check the unit boundary: no literal unit conversion (/ 1000.0, * 1000.0,
                              PI / 180, to_radians, to_degrees) in the libraries outside
                              crates/chain/src/units.rs (tests, benches, examples and doc comments
                              excepted); no function over 100 lines in crates/*/src or
                              python/src; every section of docs/*.md with figures carries a
                              `Recorded YYYY-MM-DD on <machine>` line or a `Checked by `test`` line
                              naming an existing test (generated documents excepted).";

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let root = workspace_root();
    std::env::set_current_dir(&root).with_context(|| format!("entering {}", root.display()))?;
    match args.first().map(String::as_str) {
        Some("reproduce-paper") => reproduce(args.iter().any(|a| a == "--check")),
        Some("bless-golden") => bless(),
        Some("bench") => {
            let baseline = args.iter().position(|a| a == "--baseline").and_then(|k| args.get(k + 1));
            bench::bench(args.iter().any(|a| a == "--json"), baseline.map(String::as_str))
        }
        Some("measure") => bench::measure_task(&args[1..]),
        Some("real-data") => real_data::real_data(),
        Some("wheel") => wheel(),
        Some("package") => package(),
        Some("deps") => deps(),
        Some("tidy") => tidy(),
        Some("-h" | "--help") | None => {
            println!("{HELP}");
            Ok(())
        }
        Some(other) => bail!("unknown task `{other}`\n\n{HELP}"),
    }
}

/// The Python package's abi3 wheel, built by maturin into `target/wheels/` (emptied first, so that the
/// one wheel there is this build's).
fn wheel() -> Result<()> {
    let out = Path::new("target/wheels");
    if out.exists() {
        std::fs::remove_dir_all(out).with_context(|| format!("emptying {}", out.display()))?;
    }
    let mut maturin = Command::new(std::env::var("MATURIN").unwrap_or_else(|_| "maturin".into()));
    maturin.args(["build", "--release", "--manifest-path", "python/Cargo.toml", "--out"]).arg(out);
    run(&mut maturin).context("building the wheel needs maturin on PATH (pip install maturin)")?;
    for entry in std::fs::read_dir(out)? {
        println!("{}", entry?.path().display());
    }
    Ok(())
}

/// The workspace's members marked `publish = false` (`cargo metadata` lists them with no registry).
fn unpublished() -> Result<Vec<String>> {
    let out = cargo().args(["metadata", "--no-deps", "--format-version", "1", "--locked"]).output()?;
    if !out.status.success() {
        bail!("cargo metadata failed: {}", String::from_utf8_lossy(&out.stderr));
    }
    let metadata: serde_json::Value = serde_json::from_slice(&out.stdout)?;
    let packages = metadata["packages"].as_array().context("cargo metadata lists no packages")?;
    let mut names: Vec<String> = packages
        .iter()
        .filter(|p| p["publish"].as_array().is_some_and(Vec::is_empty))
        .filter_map(|p| p["name"].as_str().map(String::from))
        .collect();
    names.sort();
    Ok(names)
}

/// `cargo package --workspace`, the members marked `publish = false` excluded. Verified in a target
/// directory of its own (`target/package-verify`), whose builds of our own crates are removed first: a
/// packaged crate is a registry crate to cargo, fingerprinted by name and version, not by content, so a
/// build of an earlier `0.1.0` would otherwise be taken for this one's.
fn package() -> Result<()> {
    // Cargo verifies each package against the others through a local registry it extracts into
    // CARGO_HOME by name and version: an earlier 0.1.0's extracted sources would stand for today's (a
    // type added to thermokin-chain missing when thermokin-deform verified). Ours go first.
    forget_extracted_packages()?;
    let verify = Path::new("target/package-verify");
    for dir in ["debug/deps", "debug/.fingerprint", "debug/build"] {
        let Ok(entries) = std::fs::read_dir(verify.join(dir)) else { continue };
        for entry in entries {
            let path = entry?.path();
            let name = path.file_name().and_then(|n| n.to_str()).unwrap_or_default();
            if name.starts_with("thermokin") || name.starts_with("libthermokin") {
                if path.is_dir() { std::fs::remove_dir_all(&path)? } else { std::fs::remove_file(&path)? }
            }
        }
    }
    let mut cmd = cargo();
    cmd.args(["package", "--workspace", "--locked", "--target-dir"]).arg(verify);
    // The verification compiles every package and its dependencies from scratch (its own target
    // directory, the default dev profile) to learn whether the packaged sources build, which debug
    // information does not decide: without it the step took 220 s instead of 254 on 2 cores (AMD EPYC,
    // 2026-11-30), a tenth of CI's half hour.
    cmd.env("CARGO_PROFILE_DEV_DEBUG", "0").env("CARGO_INCREMENTAL", "0");
    for name in unpublished()? {
        cmd.args(["--exclude", &name]);
    }
    run(&mut cmd)
}

/// Removes this workspace's packages (`thermokin-*`) from CARGO_HOME's extracted sources and cache of
/// every registry — none of ours comes from crates.io, so only earlier verifications' copies are there.
fn forget_extracted_packages() -> Result<()> {
    let home = std::env::var_os("CARGO_HOME")
        .map(PathBuf::from)
        .or_else(|| std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".cargo")));
    let Some(home) = home else { return Ok(()) };
    for kind in ["src", "cache"] {
        let Ok(registries) = std::fs::read_dir(home.join("registry").join(kind)) else { continue };
        for registry in registries {
            let Ok(entries) = std::fs::read_dir(registry?.path()) else { continue };
            for entry in entries {
                let path = entry?.path();
                if path.file_name().and_then(|n| n.to_str()).is_some_and(|n| n.starts_with("thermokin-")) {
                    if path.is_dir() { std::fs::remove_dir_all(&path)? } else { std::fs::remove_file(&path)? }
                }
            }
        }
    }
    Ok(())
}

pub(crate) fn workspace_root() -> PathBuf {
    let here = Path::new(env!("CARGO_MANIFEST_DIR"));
    here.parent().map_or_else(|| here.to_path_buf(), Path::to_path_buf)
}

pub(crate) fn cargo() -> Command {
    Command::new(std::env::var("CARGO").unwrap_or_else(|_| "cargo".into()))
}

pub(crate) fn run(cmd: &mut Command) -> Result<()> {
    let status = cmd.status().with_context(|| format!("running {cmd:?}"))?;
    if !status.success() {
        bail!("{cmd:?} failed with {status}");
    }
    Ok(())
}

const GOLDEN: &str = "fixtures/golden/paper-reproduction.json";

/// Where `reproduce-paper` writes: under `target/`, never over a tracked file.
const OUT: &str = "target/paper-reproduction";

fn thermokin(report: &str, plots: &str, extra: &[&str]) -> Result<()> {
    // No `--quiet`: on a cold checkout the release build takes minutes, and cargo's own progress is the
    // only sign of life until the run starts.
    eprintln!("reproduce-paper: building the release binary (minutes on a cold checkout), then running");
    let mut cmd = cargo();
    cmd.args(["run", "--release", "--package", "thermokin", "--", "reproduce-paper"]);
    cmd.args(["--report", report, "--plot", plots]);
    cmd.args(extra);
    run(&mut cmd)
}

fn reproduce(check: bool) -> Result<()> {
    let img = format!("{OUT}/img");
    std::fs::create_dir_all(&img)?;
    let report = format!("{OUT}/paper-reproduction.md");
    if check {
        let json = format!("{OUT}/paper-reproduction.json");
        thermokin(&report, &img, &["--json", &json, "--check", GOLDEN])?;
    } else {
        thermokin(&report, &img, &[])?;
    }
    println!("report: {report} (plots in {img}/); `cargo xtask bless-golden` updates docs/ and {GOLDEN}");
    Ok(())
}

/// Regenerates the committed outputs: `docs/paper-reproduction.md`, `docs/img/` and the golden JSON.
fn bless() -> Result<()> {
    std::fs::create_dir_all("fixtures/golden")?;
    std::fs::create_dir_all("docs/img")?;
    thermokin("docs/paper-reproduction.md", "docs/img", &["--json", GOLDEN])?;
    println!("blessed: docs/paper-reproduction.md, docs/img/, {GOLDEN}");
    Ok(())
}

/// Each library crate and the workspace crates it may depend on (directly or not): the layering of
/// ARCHITECTURE.md. Anything else of ours in its tree is an error, and so are file-format crates outside
/// `thermokin-io` and the CLI parser anywhere in a library.
const ALLOWED: &[(&str, &[&str])] = &[
    ("thermokin-chain", &[]),
    // Data only: the files the README's commands name, built into the binary that links it.
    ("thermokin-bundled", &[]),
    ("thermokin-deform", &["thermokin-chain"]),
    ("thermokin-ik", &["thermokin-chain"]),
    ("thermokin-urdf", &["thermokin-chain"]),
    // Readers sit below the algorithms: io builds chains, tables and measurement data (all in chain and
    // deform) and knows no identification, IK or compensation.
    ("thermokin-io", &["thermokin-chain", "thermokin-deform", "thermokin-urdf"]),
    // Identification: the model of effects, its fit and identifiability, on the chain and the calibrated
    // robot it identifies; no file format.
    ("thermokin-identify", &["thermokin-chain", "thermokin-deform"]),
    // The diagnosis stands on identification; it reads no file (the front ends do).
    ("thermokin-diagnose", &["thermokin-chain", "thermokin-deform", "thermokin-identify"]),
    // The planner shares identification's model and Jacobians with the diagnosis, beside it, not on it.
    ("thermokin-planner", &["thermokin-chain", "thermokin-deform", "thermokin-identify"]),
    // The compensation's writers put results in degrees through io's one unit boundary.
    (
        "thermokin-compensate",
        &["thermokin-chain", "thermokin-deform", "thermokin-ik", "thermokin-io", "thermokin-urdf"],
    ),
    // The paper crate reads the authors' rows through io and reruns the case studies.
    (
        "thermokin-paper",
        &[
            "thermokin-chain",
            "thermokin-deform",
            "thermokin-io",
            "thermokin-urdf",
            "thermokin-ik",
            "thermokin-compensate",
        ],
    ),
    // Plots of a compensation run and of a diagnosis: drawn in memory, written by the front end.
    (
        "thermokin-plot",
        &[
            "thermokin-chain",
            "thermokin-deform",
            "thermokin-io",
            "thermokin-urdf",
            "thermokin-ik",
            "thermokin-compensate",
            "thermokin-identify",
            "thermokin-diagnose",
        ],
    ),
    // The diagnosis and the plan as a page: it reads their reports and writes a string; no file format.
    (
        "thermokin-report",
        &["thermokin-chain", "thermokin-deform", "thermokin-identify", "thermokin-diagnose", "thermokin-planner"],
    ),
    // The Python front end calls the libraries the CLI calls, never the CLI (nor the paper crate).
    (
        "thermokin-python",
        &[
            "thermokin-chain",
            "thermokin-deform",
            "thermokin-io",
            "thermokin-urdf",
            "thermokin-ik",
            "thermokin-compensate",
            "thermokin-identify",
            "thermokin-diagnose",
            "thermokin-planner",
            "thermokin-report",
        ],
    ),
];

/// File-format and CLI crates, allowed only where named.
/// (`thermokin-paper`, `thermokin-compensate` and `thermokin-diagnose` see them only through `thermokin-io`.)
const FORMAT_CRATES: &[(&str, &[&str])] = &[
    ("toml", &["thermokin-io", "thermokin-compensate", "thermokin-paper", "thermokin-plot", "thermokin-python"]),
    ("csv", &["thermokin-io", "thermokin-compensate", "thermokin-paper", "thermokin-plot", "thermokin-python"]),
    ("clap", &[]),
];

fn deps() -> Result<()> {
    let mut bad = Vec::new();
    for (krate, allowed) in ALLOWED {
        let out = cargo()
            .args(["tree", "--edges", "normal", "--prefix", "none", "--format", "{p}", "--package", krate])
            .output()
            .context("running cargo tree")?;
        if !out.status.success() {
            bail!("cargo tree failed for {krate}: {}", String::from_utf8_lossy(&out.stderr));
        }
        let tree = String::from_utf8_lossy(&out.stdout);
        let names: std::collections::BTreeSet<&str> =
            tree.lines().filter_map(|l| l.split_whitespace().next()).collect();
        for name in &names {
            if name.starts_with("thermokin") && name != krate && !allowed.contains(name) {
                bad.push(format!("{krate} depends on {name}"));
            }
        }
        for (format, users) in FORMAT_CRATES {
            if names.contains(format) && !users.contains(krate) {
                bad.push(format!("{krate} depends on {format}"));
            }
        }
    }
    let root = workspace_root();
    let mut modules = 0;
    for dir in crate_dirs(&root)? {
        let (count, circles) = module_circles(&dir.join("src"))?;
        modules += count;
        let shown = dir.strip_prefix(&root).unwrap_or(&dir).display().to_string();
        bad.extend(circles.into_iter().map(|c| format!("{shown}: modules in a circle: {}", c.join(" → "))));
    }
    let layers = documented_layers(&std::fs::read_to_string(root.join("ARCHITECTURE.md"))?, "diagnose-layers");
    let breaches = layer_breaches(&root.join("crates/diagnose/src"), &layers)?;
    bad.extend(breaches.into_iter().map(|b| format!("crates/diagnose: {b}")));
    if bad.is_empty() {
        println!(
            "deps: dependency direction ok ({} crates checked; {modules} modules, none in a circle; the diagnosis's {} layers only look down)",
            ALLOWED.len(),
            layers.len()
        );
        Ok(())
    } else {
        bail!("dependency direction broken:\n  {}", bad.join("\n  "))
    }
}

/// The layers ARCHITECTURE.md lists between `<!-- {name}:begin -->` and `<!-- {name}:end -->`, bottom
/// first: per numbered line, the backticked module names before its dash.
fn documented_layers(text: &str, name: &str) -> Vec<Vec<String>> {
    let (Some(start), Some(end)) =
        (text.find(&format!("<!-- {name}:begin -->")), text.find(&format!("<!-- {name}:end -->")))
    else {
        return Vec::new();
    };
    text[start..end]
        .lines()
        .filter(|l| l.chars().next().is_some_and(|c| c.is_ascii_digit()))
        .map(|l| l.split(" — ").next().unwrap_or("").split('`').skip(1).step_by(2).map(str::to_string).collect())
        .collect()
}

/// Within one crate's flat `src/`, each reference of a module to one in a higher layer of `layers`
/// (bottom first), and each module in no layer or in two — the roots (`lib.rs`, `main.rs`) excepted.
fn layer_breaches(src: &Path, layers: &[Vec<String>]) -> Result<Vec<String>> {
    let layer_of = |m: &str| layers.iter().position(|l| l.iter().any(|n| n == m));
    let mut out = Vec::new();
    for (k, layer) in layers.iter().enumerate() {
        for m in layer {
            if layers.iter().skip(k + 1).any(|l| l.contains(m)) {
                out.push(format!("module `{m}` listed in two layers"));
            }
        }
    }
    let mut files: Vec<_> = std::fs::read_dir(src)?.filter_map(|e| e.ok().map(|e| e.path())).collect();
    files.sort();
    let stems: Vec<String> = files
        .iter()
        .filter(|p| p.extension().is_some_and(|e| e == "rs"))
        .filter_map(|p| p.file_stem().and_then(|s| s.to_str()).map(str::to_string))
        .filter(|s| s != "lib" && s != "main")
        .collect();
    for m in &stems {
        let Some(at) = layer_of(m) else {
            out.push(format!("module `{m}` is in no layer of ARCHITECTURE.md's list"));
            continue;
        };
        let text = std::fs::read_to_string(src.join(format!("{m}.rs")))?;
        for r in crate_references(&text).into_iter().filter(|r| r != m && stems.contains(r)) {
            if let Some(above) = layer_of(&r).filter(|&l| l > at) {
                out.push(format!("`{m}` (layer {}) uses `{r}` (layer {}), which stands above it", at + 1, above + 1));
            }
        }
    }
    Ok(out)
}

/// The modules `crate::NAME` names in one source file's text, tests (everything after `#[cfg(test)]`)
/// and comments excepted.
fn crate_references(text: &str) -> std::collections::BTreeSet<String> {
    let mut out = std::collections::BTreeSet::new();
    for line in text.lines() {
        let code = line.trim_start();
        if code.starts_with("#[cfg(test)]") {
            break;
        }
        if code.starts_with("//") {
            continue;
        }
        for piece in code.split("crate::").skip(1) {
            let name: String = piece.chars().take_while(|c| c.is_alphanumeric() || *c == '_').collect();
            if !name.is_empty() {
                out.insert(name);
            }
        }
    }
    out
}

/// Within one crate's flat `src/` (each module a file), the circles of `crate::` references between
/// modules: dependencies inside a crate point one way too (`lib.rs`/`main.rs`, the roots, excepted).
/// Returns the module count and each circle found, as module names.
fn module_circles(src: &Path) -> Result<(usize, Vec<Vec<String>>)> {
    let mut graph: std::collections::BTreeMap<String, Vec<String>> = std::collections::BTreeMap::new();
    if !src.is_dir() {
        return Ok((0, Vec::new()));
    }
    let mut texts = Vec::new();
    for entry in std::fs::read_dir(src)? {
        let path = entry?.path();
        let Some(stem) = path.file_stem().and_then(|s| s.to_str()).map(str::to_string) else { continue };
        if path.extension().is_some_and(|e| e == "rs") && stem != "lib" && stem != "main" {
            texts.push((stem, std::fs::read_to_string(&path)?));
        }
    }
    let names: std::collections::BTreeSet<String> = texts.iter().map(|(n, _)| n.clone()).collect();
    for (name, text) in &texts {
        let refs = crate_references(text).into_iter().filter(|r| r != name && names.contains(r)).collect();
        graph.insert(name.clone(), refs);
    }
    // Depth-first search: a reference back to a module on the current path closes a circle.
    fn visit(
        node: &str,
        graph: &std::collections::BTreeMap<String, Vec<String>>,
        path: &mut Vec<String>,
        done: &mut std::collections::BTreeSet<String>,
        circles: &mut Vec<Vec<String>>,
    ) {
        if let Some(at) = path.iter().position(|p| p == node) {
            let mut circle = path[at..].to_vec();
            circle.push(node.to_string());
            circles.push(circle);
            return;
        }
        if done.contains(node) {
            return;
        }
        path.push(node.to_string());
        for next in graph.get(node).into_iter().flatten() {
            visit(next, graph, path, done, circles);
        }
        path.pop();
        done.insert(node.to_string());
    }
    let (mut done, mut circles) = (std::collections::BTreeSet::new(), Vec::new());
    for node in graph.keys() {
        visit(node, &graph, &mut Vec::new(), &mut done, &mut circles);
    }
    Ok((graph.len(), circles))
}

/// The one module allowed to convert units.
const UNITS_MODULE: &str = "crates/chain/src/units.rs";

/// Literal unit conversions: a length between metres and millimetres, an angle between degrees and
/// radians, written out instead of called through [`UNITS_MODULE`].
const STRAY_CONVERSIONS: &[&str] =
    &["/ 1000.0", "* 1000.0", "1000.0 *", "/ 1e3", "* 1e3", "PI / 180", "180.0 / PI", "to_radians", "to_degrees"];

/// The stray conversions in one source file's text: (1-based line, the line), doc comments, comments and
/// `#[cfg(test)]` modules (everything after the attribute) excepted.
fn stray_conversions(text: &str) -> Vec<(usize, String)> {
    let mut out = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let code = line.trim_start();
        if code.starts_with("#[cfg(test)]") {
            break;
        }
        if code.starts_with("//") {
            continue;
        }
        let code = code.split(" //").next().unwrap_or(code);
        if STRAY_CONVERSIONS.iter().any(|p| code.contains(p)) {
            out.push((i + 1, line.trim().to_string()));
        }
    }
    out
}

/// The workspace's crate directories: `crates/*` and the Python binding (`python/`).
fn crate_dirs(root: &Path) -> Result<Vec<PathBuf>> {
    let mut dirs: Vec<PathBuf> =
        std::fs::read_dir(root.join("crates"))?.filter_map(|e| e.ok().map(|e| e.path())).collect();
    dirs.push(root.join("python"));
    dirs.sort();
    Ok(dirs)
}

/// Every library source file: `crates/*/src/**/*.rs` and `python/src`, the test-support crate excepted.
fn library_sources(root: &Path) -> Result<Vec<PathBuf>> {
    let mut files = Vec::new();
    let mut stack: Vec<PathBuf> = crate_dirs(root)?
        .into_iter()
        .map(|d| d.join("src"))
        .filter(|p| p.is_dir() && !p.starts_with(root.join("crates/testdata")))
        .collect();
    while let Some(dir) = stack.pop() {
        for entry in std::fs::read_dir(&dir)? {
            let path = entry?.path();
            if path.is_dir() {
                stack.push(path);
            } else if path.extension().is_some_and(|e| e == "rs") {
                files.push(path);
            }
        }
    }
    files.sort();
    Ok(files)
}

/// The longest a function of the libraries and front ends may be, in lines from its signature to its
/// closing brace: past it, split it by meaning.
const MAX_FUNCTION_LINES: usize = 100;

/// The functions of one source file's text longer than [`MAX_FUNCTION_LINES`]: (1-based line of the
/// signature, name, lines). A function is an item `fn` (after `pub`, `const`, `async`, `unsafe`) whose
/// body closes on a line holding only `}` at the signature's indentation, as rustfmt writes it.
fn long_functions(text: &str) -> Vec<(usize, String, usize)> {
    let lines: Vec<&str> = text.lines().collect();
    let mut out = Vec::new();
    for (i, line) in lines.iter().enumerate() {
        let code = line.trim_start();
        let indent = &line[..line.len() - code.len()];
        let mut rest = code;
        for prefix in ["pub(crate) ", "pub(super) ", "pub ", "const ", "async ", "unsafe ", "extern \"C\" "] {
            rest = rest.strip_prefix(prefix).unwrap_or(rest);
        }
        let Some(signature) = rest.strip_prefix("fn ") else { continue };
        let name: String = signature.chars().take_while(|c| c.is_alphanumeric() || *c == '_').collect();
        // The body opens on the signature's last line; a declaration ends with `;` first.
        let Some(open) = (i..lines.len()).find(|&k| lines[k].contains('{') || lines[k].trim_end().ends_with(';'))
        else {
            continue;
        };
        if !lines[open].contains('{') || lines[open].trim_end().ends_with('}') {
            continue;
        }
        let closing = format!("{indent}}}");
        if let Some(end) = (open + 1..lines.len()).find(|&k| lines[k].trim_end() == closing) {
            let length = end - i + 1;
            if length > MAX_FUNCTION_LINES {
                out.push((i + 1, name, length));
            }
        }
    }
    out
}

/// A figure in prose: a digit, a decimal point, a digit (`0.456`, `14.4`), outside code.
fn has_figure(line: &str) -> bool {
    let b = line.as_bytes();
    (1..b.len().saturating_sub(1)).any(|i| b[i] == b'.' && b[i - 1].is_ascii_digit() && b[i + 1].is_ascii_digit())
}

/// How a section of a document may carry figures: a record line (`Recorded YYYY-MM-DD …`: when and on
/// what machine it was measured, stated as a record and not kept true by anything), or a line
/// `Checked by `file::test`` naming a test that reruns and compares them.
fn record_line(line: &str) -> Option<Result<(), String>> {
    let line = line.trim_start_matches(['*', '_', ' ']);
    if let Some(rest) = line.strip_prefix("Recorded ") {
        let date = rest.get(..10).unwrap_or("");
        let ok = date.len() == 10
            && date.bytes().enumerate().all(|(i, c)| if i == 4 || i == 7 { c == b'-' } else { c.is_ascii_digit() });
        return Some(if ok && rest.contains(" on ") {
            Ok(())
        } else {
            Err(format!("`{line}`: a record says `Recorded YYYY-MM-DD on <machine>`"))
        });
    }
    line.strip_prefix("Checked by ").map(|rest| {
        let names: Vec<&str> = rest.split('`').skip(1).step_by(2).collect();
        if names.is_empty() { Err(format!("`{line}`: name the test in backticks")) } else { Ok(()) }
    })
}

/// The sections of a Markdown document that carry figures without a record or a check, and the malformed
/// record lines: (1-based line of the heading or the record, what is wrong). A section is covered by its
/// own record or by one of the sections it sits in (a `###` under a recorded `##`); code blocks and
/// headings are not prose. A generated document (its first line `Generated by …`) is its command's.
fn unrecorded_sections(text: &str, test_exists: &dyn Fn(&str) -> bool) -> Vec<(usize, String)> {
    if text
        .lines()
        .find(|l| !l.trim().is_empty() && !l.starts_with('#'))
        .is_some_and(|l| l.starts_with("Generated by "))
    {
        return Vec::new();
    }
    struct Section {
        level: usize,
        line: usize,
        heading: String,
        figures: bool,
        recorded: bool,
    }
    let mut out = Vec::new();
    let mut open: Vec<Section> = Vec::new();
    let close = |open: &mut Vec<Section>, level: usize, out: &mut Vec<(usize, String)>| {
        while open.last().is_some_and(|s| s.level >= level) {
            let s = open.pop().expect("checked above");
            let covered = s.recorded || open.iter().any(|p| p.recorded);
            if s.figures && !covered {
                out.push((s.line, format!("section `{}` carries figures without a record or a check", s.heading)));
            }
        }
    };
    let mut fenced = false;
    for (i, line) in text.lines().enumerate() {
        if line.starts_with("```") {
            fenced = !fenced;
            continue;
        }
        if fenced {
            continue;
        }
        let level = line.bytes().take_while(|&c| c == b'#').count();
        if level > 0 && line.as_bytes().get(level) == Some(&b' ') {
            close(&mut open, level, &mut out);
            let heading = line[level..].trim().to_string();
            open.push(Section { level, line: i + 1, heading, figures: false, recorded: false });
            continue;
        }
        let Some(section) = open.last_mut() else { continue };
        match record_line(line) {
            Some(Ok(())) => {
                let rest = line.split('`').skip(1).step_by(2).filter(|n| !test_exists(n)).collect::<Vec<_>>();
                if line.trim_start_matches(['*', '_', ' ']).starts_with("Checked by ") && !rest.is_empty() {
                    out.push((i + 1, format!("no test named {}", rest.join(", "))));
                }
                section.recorded = true;
            }
            Some(Err(why)) => out.push((i + 1, why)),
            None => {
                let prose: String = line.split('`').step_by(2).collect::<Vec<_>>().join(" ");
                section.figures |= has_figure(&prose);
            }
        }
    }
    close(&mut open, 1, &mut out);
    out.sort();
    out
}

/// Whether `name` (`file.rs::function`, or a function alone) is a test function somewhere under
/// `crates/`, `python/tests` or `xtask/` — what a `Checked by` line may cite.
fn test_exists(root: &Path, name: &str) -> bool {
    let function = name.rsplit("::").next().unwrap_or(name).trim_end_matches("()");
    let file = name.contains("::").then(|| name.split("::").next().unwrap_or(""));
    let mut stack = vec![root.join("crates"), root.join("python/tests"), root.join("xtask")];
    while let Some(dir) = stack.pop() {
        let Ok(entries) = std::fs::read_dir(&dir) else { continue };
        for path in entries.filter_map(|e| e.ok().map(|e| e.path())) {
            if path.is_dir() {
                stack.push(path);
                continue;
            }
            let named = file.is_none_or(|f| path.file_name().is_some_and(|n| n.to_string_lossy() == f));
            let source = path.extension().is_some_and(|e| e == "rs" || e == "py");
            if named
                && source
                && std::fs::read_to_string(&path)
                    .is_ok_and(|t| t.contains(&format!("fn {function}(")) || t.contains(&format!("def {function}(")))
            {
                return true;
            }
        }
    }
    false
}

/// The documents whose figures [`unrecorded_sections`] checks: every `docs/*.md`.
fn documents(root: &Path) -> Result<Vec<PathBuf>> {
    let mut docs: Vec<PathBuf> = std::fs::read_dir(root.join("docs"))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e == "md"))
        .collect();
    docs.sort();
    Ok(docs)
}

/// The source files a document names, as workspace paths with their 1-based line: `crates/X/src/Y.rs`
/// (or `…/tests/…`, `…/benches/…`) written out, and `thermokin-X/src/Y.rs` for the crate of that name.
fn source_paths(text: &str) -> Vec<(usize, String)> {
    let mut out = Vec::new();
    for (i, line) in text.lines().enumerate() {
        for (prefix, replace) in [("crates/", "crates/"), ("thermokin-", "crates/")] {
            for piece in line.split(prefix).skip(1) {
                let path: String =
                    piece.chars().take_while(|c| c.is_alphanumeric() || matches!(c, '_' | '-' | '/' | '.')).collect();
                let path = path.trim_end_matches('.');
                let mut parts = path.splitn(2, '/');
                let (Some(krate), Some(rest)) = (parts.next(), parts.next()) else { continue };
                let kept = ["src/", "tests/", "benches/"].iter().any(|d| rest.starts_with(d));
                if kept && rest.ends_with(".rs") {
                    out.push((i + 1, format!("{replace}{krate}/{rest}")));
                }
            }
        }
    }
    out
}

fn tidy() -> Result<()> {
    let root = workspace_root();
    let mut bad = Vec::new();
    let mut long = Vec::new();
    let files = library_sources(&root)?;
    for path in &files {
        let relative = path.strip_prefix(&root).unwrap_or(path);
        let text = std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
        for (line, name, length) in long_functions(&text) {
            long.push(format!("{}:{line}: fn {name} has {length} lines", relative.display()));
        }
        if relative == Path::new(UNITS_MODULE) {
            continue;
        }
        for (line, code) in stray_conversions(&text) {
            bad.push(format!("{}:{line}: {code}", relative.display()));
        }
    }
    if !bad.is_empty() {
        bail!("a unit converted outside {UNITS_MODULE} (call its functions instead):\n  {}", bad.join("\n  "))
    }
    if !long.is_empty() {
        bail!("functions longer than {MAX_FUNCTION_LINES} lines (split them by meaning):\n  {}", long.join("\n  "))
    }
    let mut stale = Vec::new();
    for doc in documents(&root)? {
        let text = std::fs::read_to_string(&doc).with_context(|| format!("reading {}", doc.display()))?;
        for (line, why) in unrecorded_sections(&text, &|name| test_exists(&root, name)) {
            stale.push(format!("{}:{line}: {why}", doc.strip_prefix(&root).unwrap_or(&doc).display()));
        }
    }
    if !stale.is_empty() {
        bail!(
            "figures in docs/ that nothing keeps true (add `Recorded YYYY-MM-DD on <machine>` or `Checked by `test``):\n  {}",
            stale.join("\n  ")
        )
    }
    let mut maps = documents(&root)?;
    maps.extend(["ARCHITECTURE.md", "README.md"].map(|f| root.join(f)));
    let mut missing = Vec::new();
    for doc in &maps {
        let text = std::fs::read_to_string(doc).with_context(|| format!("reading {}", doc.display()))?;
        for (line, path) in source_paths(&text) {
            if !root.join(&path).is_file() {
                missing.push(format!("{}:{line}: {path}", doc.strip_prefix(&root).unwrap_or(doc).display()));
            }
        }
    }
    if !missing.is_empty() {
        bail!("source files the documents name that do not exist (moved or renamed?):\n  {}", missing.join("\n  "))
    }
    println!(
        "tidy: every unit conversion goes through {UNITS_MODULE}, no function over {MAX_FUNCTION_LINES} lines ({} files checked), every figure in docs/ recorded or checked, every source file the documents name exists",
        files.len()
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::panic)]

    use std::collections::BTreeSet;

    #[test]
    fn source_paths_are_read_in_both_spellings() {
        let text = "see `crates/chain/src/units.rs` and\nthe identification (`thermokin-identify/src/fit.rs`), `crates/io/tests/it/main.rs`.";
        let paths: Vec<(usize, String)> = super::source_paths(text);
        assert_eq!(
            paths,
            vec![
                (1, "crates/chain/src/units.rs".to_string()),
                (2, "crates/io/tests/it/main.rs".to_string()),
                (2, "crates/identify/src/fit.rs".to_string())
            ]
        );
    }

    #[test]
    fn a_figure_without_a_record_is_caught_and_a_recorded_or_checked_one_is_not() {
        let no_test = |_: &str| false;
        let any_test = |_: &str| true;
        let nested = "# P\n\nIn 1.5 s.\n\n### A\n\n14.4 s\n\n### B\n\n1.5 mm\n";
        assert_eq!(
            super::unrecorded_sections(nested, &no_test).len(),
            3,
            "{:?}",
            super::unrecorded_sections(nested, &no_test)
        );
        let bare = "# T\n\n## Speed\n\nIt takes 14.4 s.\n\n## Prose\n\nNo figure, 5 folds.\n";
        assert_eq!(super::unrecorded_sections(bare, &no_test).len(), 1);
        let recorded = "# T\n\n## Speed\n\nRecorded 2026-11-25 on Intel Xeon, 2 cores.\n\n### Detail\n\n0.456 mm.\n";
        assert!(super::unrecorded_sections(recorded, &no_test).is_empty());
        let undated = "## Speed\n\nRecorded yesterday on a laptop.\n\n0.456 mm\n";
        assert_eq!(super::unrecorded_sections(undated, &no_test).len(), 2);
        let checked = "## Speed\n\nChecked by `transfer.rs::ur10`.\n\n0.456 mm\n";
        assert!(super::unrecorded_sections(checked, &any_test).is_empty());
        assert_eq!(super::unrecorded_sections(checked, &no_test).len(), 1, "a check naming no test");
        let code = "## Code\n\n```\nx = 0.5\n```\n\nand `0.5` inline.\n";
        assert!(super::unrecorded_sections(code, &no_test).is_empty());
        assert!(
            super::unrecorded_sections("# R\n\nGenerated by `cargo xtask x`.\n\n## A\n\n1.5\n", &no_test).is_empty()
        );
        // The project's documents hold none.
        let root = super::workspace_root();
        for doc in super::documents(&root).unwrap() {
            let text = std::fs::read_to_string(&doc).unwrap();
            let bad = super::unrecorded_sections(&text, &|n| super::test_exists(&root, n));
            assert!(bad.is_empty(), "{}: {bad:?}", doc.display());
        }
        assert!(
            super::test_exists(&root, "xtask/src/main.rs::a_long_function_is_caught_and_a_short_one_is_not")
                || super::test_exists(&root, "main.rs::a_long_function_is_caught_and_a_short_one_is_not")
        );
        assert!(!super::test_exists(&root, "no_such_test_anywhere"));
    }

    #[test]
    fn a_long_function_is_caught_and_a_short_one_is_not() {
        let body = |n: usize| (0..n).map(|i| format!("        let x{i} = {i};\n")).collect::<String>();
        let long = format!(
            "impl A {{\n    pub(crate) fn long(\n        a: u8,\n    ) -> u8 {{\n{}        a\n    }}\n}}\n",
            body(100)
        );
        assert_eq!(super::long_functions(&long), vec![(2, "long".to_string(), 105)]);
        let short = format!("fn short() {{\n{}}}\nfn decl();\nfn one() {{ 1 }}\n", body(90));
        assert!(super::long_functions(&short).is_empty());
        // The workspace itself holds none.
        let root = super::workspace_root();
        for path in super::library_sources(&root).unwrap() {
            let text = std::fs::read_to_string(&path).unwrap();
            assert!(super::long_functions(&text).is_empty(), "{}: {:?}", path.display(), super::long_functions(&text));
        }
    }

    #[test]
    fn the_unit_boundary_holds_and_a_stray_conversion_is_caught() {
        // The repository as it is passes ...
        super::tidy().unwrap();
        // ... and every pattern is caught in code, not in comments or tests.
        for pattern in super::STRAY_CONVERSIONS {
            let stray = format!("fn f(x: f64) -> f64 {{\n    x {pattern} 2.0\n}}\n");
            assert_eq!(super::stray_conversions(&stray).len(), 1, "{pattern} not caught");
        }
        let excused = "/// 90f64.to_radians()\n// x / 1000.0\nlet a = 1; // b * 1000.0\n#[cfg(test)]\nmod t { fn f() { 1f64.to_degrees(); } }\n";
        assert!(super::stray_conversions(excused).is_empty());
        // A library file with one: the check names it.
        let stray = "//! x\npub fn mm(m: f64) -> f64 {\n    m * 1000.0\n}\n";
        assert_eq!(super::stray_conversions(stray), vec![(3, "m * 1000.0".to_string())]);
    }

    /// A module that reaches up a layer, one in no layer and one in two are each named; the workspace's
    /// own list is read from ARCHITECTURE.md and holds every module of the diagnosis.
    #[test]
    fn a_module_that_reaches_up_a_layer_is_named() {
        let dir = std::env::temp_dir().join(format!("xtask-layers-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join("low.rs"), "use crate::high::f;\n").unwrap();
        std::fs::write(dir.join("high.rs"), "use crate::low::g;\n#[cfg(test)]\nmod t { use crate::top; }\n").unwrap();
        std::fs::write(dir.join("stray.rs"), "").unwrap();
        let text = "<!-- l:begin -->\n1. `low` — below\n2. `high`, `low` — above\n<!-- l:end -->";
        let layers = super::documented_layers(text, "l");
        assert_eq!(layers, vec![vec!["low".to_string()], vec!["high".to_string(), "low".to_string()]]);
        let found = super::layer_breaches(&dir, &layers).unwrap();
        assert!(found.iter().any(|b| b.contains("`low` (layer 1) uses `high` (layer 2)")), "{found:?}");
        assert!(found.iter().any(|b| b.contains("`stray` is in no layer")), "{found:?}");
        assert!(found.iter().any(|b| b.contains("`low` listed in two layers")), "{found:?}");
        let root = super::workspace_root();
        let ours = super::documented_layers(
            &std::fs::read_to_string(root.join("ARCHITECTURE.md")).unwrap(),
            "diagnose-layers",
        );
        assert_eq!(super::layer_breaches(&root.join("crates/diagnose/src"), &ours).unwrap(), Vec::<String>::new());
    }

    /// The rows of the ARCHITECTURE.md table between `<!-- {name}:begin -->` and `<!-- {name}:end -->`:
    /// first cell (backticks dropped), and the backticked names of the second.
    fn documented_table(name: &str) -> Vec<(String, BTreeSet<String>)> {
        let text = std::fs::read_to_string(super::workspace_root().join("ARCHITECTURE.md")).unwrap();
        let start = text.find(&format!("<!-- {name}:begin -->")).unwrap();
        let end = text.find(&format!("<!-- {name}:end -->")).unwrap();
        text[start..end]
            .lines()
            .filter(|l| l.starts_with("| `"))
            .map(|l| {
                let cells: Vec<&str> = l.split('|').map(str::trim).collect();
                let first = cells[1].split('`').nth(1).unwrap_or("").to_string();
                let named = cells[2].split('`').skip(1).step_by(2).map(str::to_string).collect();
                (first, named)
            })
            .collect()
    }

    #[test]
    fn the_documented_crate_map_is_the_workspace() {
        let root = super::workspace_root();
        let mut packages: Vec<String> = super::crate_dirs(&root)
            .unwrap()
            .into_iter()
            .map(|dir| {
                let manifest = std::fs::read_to_string(dir.join("Cargo.toml")).unwrap();
                let line = manifest.lines().find(|l| l.starts_with("name")).unwrap();
                line.split('"').nth(1).unwrap().to_string()
            })
            .collect();
        packages.sort();
        let mut documented: Vec<String> = documented_table("crates").into_iter().map(|(c, _)| c).collect();
        documented.sort();
        assert_eq!(documented, packages, "ARCHITECTURE.md's crate table and crates/ disagree: update the table");
    }

    #[test]
    fn the_documented_format_users_are_the_checked_ones() {
        let mut documented = documented_table("formats");
        documented.sort();
        let mut checked: Vec<(String, BTreeSet<String>)> = super::FORMAT_CRATES
            .iter()
            .map(|(f, users)| (f.to_string(), users.iter().map(|u| u.to_string()).collect()))
            .collect();
        checked.sort();
        assert_eq!(documented, checked, "ARCHITECTURE.md's format table and `cargo xtask deps` disagree: update both");
    }

    #[test]
    fn the_documented_layers_are_the_checked_ones() {
        let documented = documented_table("layers");
        let checked: Vec<(String, BTreeSet<String>)> = super::ALLOWED
            .iter()
            .map(|(k, allowed)| (k.to_string(), allowed.iter().map(|a| a.to_string()).collect()))
            .collect();
        let sorted = |mut v: Vec<(String, BTreeSet<String>)>| {
            v.sort();
            v
        };
        assert_eq!(
            sorted(documented),
            sorted(checked),
            "ARCHITECTURE.md's layer table and `cargo xtask deps` disagree: update both"
        );
    }

    /// Issue #62: every crate under `crates/` has a README that its crate root includes as its
    /// documentation (so that the README's example runs as a doctest).
    #[test]
    fn every_crate_documents_itself_with_its_readme() {
        let root = super::workspace_root();
        let mut crates = 0;
        for entry in std::fs::read_dir(root.join("crates")).unwrap() {
            let dir = entry.unwrap().path();
            assert!(dir.join("README.md").is_file(), "{} has no README.md", dir.display());
            let lib = dir.join("src/lib.rs");
            let root_file = if lib.exists() { lib } else { dir.join("src/main.rs") };
            let text = std::fs::read_to_string(&root_file).unwrap();
            assert!(
                text.starts_with("#![doc = include_str!(\"../README.md\")]"),
                "{} does not include its README as documentation",
                root_file.display()
            );
            crates += 1;
        }
        assert!(crates >= 14, "{crates}");
    }

    #[test]
    fn no_dangling_notes_reference_and_every_source_file_opens_with_a_doc_comment() {
        let root = super::workspace_root();
        let mut stack = vec![root.join("crates"), root.join("xtask/src"), root.join("python/src")];
        let mut checked = 0;
        while let Some(dir) = stack.pop() {
            for entry in std::fs::read_dir(&dir).unwrap() {
                let path = entry.unwrap().path();
                if path.is_dir() {
                    stack.push(path);
                } else if path.extension().is_some_and(|e| e == "rs") {
                    let text = std::fs::read_to_string(&path).unwrap();
                    // The project's own notes live in docs/; a file outside the repository is no reference.
                    assert!(
                        !text.contains(concat!("NOTES", ".md")),
                        "{} cites the shared notes file, which is not in the repository",
                        path.display()
                    );
                    let is_source = path.components().any(|c| c.as_os_str() == "src");
                    if is_source {
                        // A crate root opens with its README (its crate documentation), then its own `//!` lines.
                        let own = text.strip_prefix("#![doc = include_str!(\"../README.md\")]\n").unwrap_or(&text);
                        assert!(own.starts_with("//!"), "{} does not open with a `//!` doc comment", path.display());
                    }
                    checked += 1;
                }
            }
        }
        assert!(checked > 50, "{checked}");
    }
}
