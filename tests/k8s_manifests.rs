//! The Kubernetes manifests of docs/k8s agree with the Slurm array script that tests/slurm.rs runs:
//! no cluster can run here, so the Indexed Job's pod script and the merge Job's are run as the pods
//! would run them (`sh -c`, the manifest's environment, `/farm` moved to a scratch folder) with a
//! stand-in `caustica` that records its arguments, and so is docs/slurm/caustica-array.sbatch. For
//! every index, fresh and retried, both must ask for the same samples, seed, part and checkpoint;
//! the merge steps must merge the same files. The YAML is read by the small reader below (the
//! block style these manifests use), which fails on anything else rather than guessing.

mod common;

use common::*;
use std::path::Path;
use std::process::Command;

/// A YAML value of the block style the manifests use.
#[derive(Debug, Clone, PartialEq)]
enum Yaml {
    Map(Vec<(String, Yaml)>),
    List(Vec<Yaml>),
    Text(String),
}

impl Yaml {
    fn get(&self, key: &str) -> &Yaml {
        match self {
            Yaml::Map(entries) => &entries.iter().find(|(k, _)| k == key).unwrap_or_else(|| panic!("no key {key}")).1,
            _ => panic!("{key}: not a mapping"),
        }
    }
    fn at(&self, path: &str) -> &Yaml {
        path.split('.').fold(self, |v, key| match key.parse::<usize>() {
            Ok(i) => match v {
                Yaml::List(items) => &items[i],
                _ => panic!("{path}: not a list at {key}"),
            },
            Err(_) => v.get(key),
        })
    }
    fn text(&self) -> &str {
        match self {
            Yaml::Text(t) => t,
            other => panic!("not text: {other:?}"),
        }
    }
    fn list(&self) -> &[Yaml] {
        match self {
            Yaml::List(items) => items,
            other => panic!("not a list: {other:?}"),
        }
    }
}

/// Lines with their indentation; comments and blank lines outside block scalars dropped later.
struct Reader {
    lines: Vec<String>,
    at: usize,
}

fn indent(line: &str) -> usize {
    line.len() - line.trim_start_matches(' ').len()
}

fn is_content(line: &str) -> bool {
    let t = line.trim();
    !t.is_empty() && !t.starts_with('#')
}

impl Reader {
    fn parse(text: &str) -> Yaml {
        assert!(!text.contains('\t'), "tabs in YAML");
        let mut reader = Reader { lines: text.lines().map(str::to_owned).collect(), at: 0 };
        reader.skip();
        let value = reader.block(0);
        reader.skip();
        assert_eq!(reader.at, reader.lines.len(), "unread YAML from line {}", reader.at + 1);
        value
    }

    fn skip(&mut self) {
        while self.at < self.lines.len() && !is_content(&self.lines[self.at]) {
            self.at += 1;
        }
    }

    /// The next content line's indentation, if any.
    fn next_indent(&mut self) -> Option<usize> {
        self.skip();
        self.lines.get(self.at).map(|l| indent(l))
    }

    /// A mapping or list whose lines are indented `n`.
    fn block(&mut self, n: usize) -> Yaml {
        if self.lines[self.at][n..].starts_with("- ") {
            let mut items = vec![];
            while self.next_indent() == Some(n) && self.lines[self.at][n..].starts_with("- ") {
                // "- key: value" opens a mapping indented n + 2: read it as if the dash were a space.
                let line = &mut self.lines[self.at];
                line.replace_range(n..n + 2, "  ");
                if line.trim() == "|" {
                    self.at += 1;
                    items.push(self.literal(n));
                } else if line[n + 2..].contains(": ") || line.ends_with(':') {
                    items.push(self.block(n + 2));
                } else {
                    items.push(Yaml::Text(scalar(line.trim())));
                    self.at += 1;
                }
            }
            return Yaml::List(items);
        }
        let mut entries = vec![];
        while self.next_indent() == Some(n) && !self.lines[self.at][n..].starts_with("- ") {
            let line = self.lines[self.at].clone();
            let (key, rest) = line.trim().split_once(':').unwrap_or_else(|| panic!("line {}: no key", self.at + 1));
            let rest = rest.trim();
            self.at += 1;
            let value = match rest {
                "" => match self.next_indent() {
                    Some(m) if m > n || (m == n && self.lines[self.at][n..].starts_with("- ")) => self.block(m),
                    _ => Yaml::Text(String::new()),
                },
                "|" => self.literal(n),
                _ if rest.starts_with('[') => {
                    let inner = rest.strip_prefix('[').and_then(|r| r.strip_suffix(']')).expect("a one-line flow list");
                    Yaml::List(inner.split(", ").map(|s| Yaml::Text(scalar(s))).collect())
                }
                _ => Yaml::Text(scalar(rest)),
            };
            entries.push((key.to_owned(), value));
        }
        Yaml::Map(entries)
    }

    /// A `|` block scalar under a key indented `n`: its lines, less their common indentation.
    fn literal(&mut self, n: usize) -> Yaml {
        let mut lines = vec![];
        while let Some(line) = self.lines.get(self.at) {
            if !line.trim().is_empty() && indent(line) <= n {
                break;
            }
            lines.push(line.clone());
            self.at += 1;
        }
        while lines.last().is_some_and(|l| l.trim().is_empty()) {
            lines.pop();
        }
        let cut = lines.iter().filter(|l| !l.trim().is_empty()).map(|l| indent(l)).min().unwrap_or(0);
        Yaml::Text(lines.iter().map(|l| format!("{}\n", l.get(cut..).unwrap_or(""))).collect())
    }
}

/// A plain or double-quoted scalar (the manifests use no escapes).
fn scalar(s: &str) -> String {
    let s = s.trim();
    s.strip_prefix('"').and_then(|r| r.strip_suffix('"')).unwrap_or(s).to_owned()
}

fn manifest(name: &str) -> Yaml {
    Reader::parse(&std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/k8s").join(name)).unwrap())
}

/// A folder with a stand-in `caustica` that appends its arguments, one per line, then a blank
/// line, to calls.txt.
fn stand_in(dir: &Path) {
    let bin = dir.join("bin");
    std::fs::create_dir_all(&bin).unwrap();
    let script = format!(
        "#!/bin/sh\nfor a in \"$@\"; do echo \"$a\"; done >> {0}/calls.txt\necho >> {0}/calls.txt\n",
        dir.display()
    );
    std::fs::write(bin.join("caustica"), script).unwrap();
    Command::new("chmod").arg("+x").arg(bin.join("caustica")).status().unwrap();
}

/// Runs `shell` with `script` (an argument list) in `dir` with the stand-in first on PATH and
/// `env`; returns the stand-in's calls, each its argument list, and clears them.
fn calls(dir: &Path, shell: &[&str], env: &[(&str, String)]) -> Vec<Vec<String>> {
    let path = format!("{}:{}", dir.join("bin").display(), std::env::var("PATH").unwrap_or_default());
    let o = Command::new(shell[0])
        .args(&shell[1..])
        .current_dir(dir)
        .env("PATH", path)
        .envs(env.iter().map(|(k, v)| (*k, v)))
        .output()
        .unwrap();
    assert!(o.status.success(), "{shell:?}: {}", String::from_utf8_lossy(&o.stderr));
    let text = std::fs::read_to_string(dir.join("calls.txt")).unwrap_or_default();
    std::fs::remove_file(dir.join("calls.txt")).ok();
    text.split("\n\n").filter(|c| !c.is_empty()).map(|c| c.lines().map(str::to_owned).collect()).collect()
}

/// What a render call decides about the farm, paths reduced to their file names: the samples (the
/// offset or a resume), their count, the seed, the part and checkpoint, the checkpoint interval.
/// `--time` (Slurm's limit has no Kubernetes counterpart) and the scene path are left out.
fn decisions(call: &[String]) -> Vec<String> {
    assert_eq!(call[0], "render", "{call:?}");
    let mut out = vec![];
    let mut args = call[2..].iter();
    while let Some(flag) = args.next() {
        match flag.as_str() {
            "--resume" | "--json" => out.push(flag.clone()),
            "--time" => {
                args.next();
            }
            "-o" | "--checkpoint" => {
                let path = args.next().unwrap();
                out.push(format!("{flag} {}", Path::new(path).file_name().unwrap().to_string_lossy()))
            }
            _ => out.push(format!("{flag} {}", args.next().unwrap())),
        }
    }
    out.sort();
    out
}

/// The sbatch script's array size and `${NAME:-default}` defaults.
fn sbatch_defaults(script: &str, name: &str) -> String {
    let prefix = format!("{name}=${{{name}:-");
    let line = script.lines().find_map(|l| l.strip_prefix(&prefix)).unwrap_or_else(|| panic!("no {name} default"));
    line.strip_suffix('}').unwrap().to_owned()
}

#[test]
fn indexed_job_renders_the_sample_ranges_of_the_slurm_array_and_merges_the_same_parts() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let sbatch = std::fs::read_to_string(root.join("docs/slurm/caustica-array.sbatch")).unwrap();
    let job = manifest("caustica-indexed-job.yaml");
    let merge_job = manifest("caustica-merge-job.yaml");
    let dir = temp_dir("k8s-manifests");
    stand_in(&dir);

    // The same number of indices as the array has tasks, and the same defaults.
    assert_eq!(job.at("kind").text(), "Job");
    assert_eq!(job.at("spec.completionMode").text(), "Indexed");
    let array = sbatch.lines().find_map(|l| l.strip_prefix("#SBATCH --array=0-")).expect("the array's size");
    let tasks: u32 = array.parse::<u32>().unwrap() + 1;
    assert_eq!(job.at("spec.completions").text(), tasks.to_string());
    let container = job.at("spec.template.spec.containers.0");
    let env: Vec<(String, String)> = container
        .get("env")
        .list()
        .iter()
        .map(|e| (e.get("name").text().to_owned(), e.get("value").text().to_owned()))
        .collect();
    let value = |name: &str| env.iter().find(|(k, _)| k == name).unwrap_or_else(|| panic!("no env {name}")).1.clone();
    for name in ["SPP_PER_TASK", "SEED"] {
        assert_eq!(value(name), sbatch_defaults(&sbatch, name), "{name}");
    }

    // Each index, fresh and then retried with its checkpoint there, asks what the array task asks.
    let command: Vec<&str> = container.get("command").list().iter().map(Yaml::text).collect();
    assert_eq!(command, ["/bin/sh", "-c"]);
    let farm = dir.join("farm");
    let pod_script = container.get("args").list()[0].text().replace("/farm", farm.to_str().unwrap());
    std::fs::create_dir_all(dir.join("parts")).unwrap();
    std::fs::create_dir_all(farm.join("parts")).unwrap();
    let sbatch_path = root.join("docs/slurm/caustica-array.sbatch");
    let mut pod_env: Vec<(&str, String)> = env.iter().map(|(k, v)| (k.as_str(), v.clone())).collect();
    pod_env.push(("JOB_COMPLETION_INDEX", String::new()));
    for k in 0..tasks {
        pod_env.last_mut().unwrap().1 = k.to_string();
        let array_env = [("SLURM_ARRAY_TASK_ID", k.to_string())];
        for retried in [false, true] {
            if retried {
                std::fs::write(dir.join(format!("parts/part-{k}.checkpoint.exr")), "").unwrap();
                std::fs::write(farm.join(format!("parts/part-{k}.checkpoint.exr")), "").unwrap();
            }
            let slurm = calls(&dir, &["bash", sbatch_path.to_str().unwrap(), "scene.toml"], &array_env);
            let pod = calls(&dir, &[command[0], command[1], &pod_script], &pod_env);
            assert_eq!(slurm.len(), 1);
            assert_eq!(pod.len(), 1);
            let expected_start = match retried {
                true => "--resume".to_owned(),
                false => format!("--sample-offset {}", k * value("SPP_PER_TASK").parse::<u32>().unwrap()),
            };
            assert!(decisions(&slurm[0]).contains(&expected_start), "task {k}: {:?}", slurm[0]);
            assert_eq!(decisions(&pod[0]), decisions(&slurm[0]), "index {k}, retried {retried}");
        }
        // The finished task's part, for the merge steps below.
        std::fs::write(dir.join(format!("parts/part-{k}.exr")), "").unwrap();
        std::fs::write(farm.join(format!("parts/part-{k}.exr")), "").unwrap();
    }

    // The merge steps merge the same parts (the checkpoints left out) into the same files.
    let wrap =
        sbatch.lines().find_map(|l| l.split_once("--wrap '")).expect("the merge command in the script's header").1;
    let slurm_merge = calls(&dir, &["bash", "-c", wrap.strip_suffix('\'').unwrap()], &[]);
    let merge_container = merge_job.at("spec.template.spec.containers.0");
    let merge_command: Vec<&str> = merge_container.get("command").list().iter().map(Yaml::text).collect();
    let merge_script = merge_container.get("args").list()[0].text().replace("/farm", farm.to_str().unwrap());
    let pod_merge = calls(&dir, &[merge_command[0], merge_command[1], &merge_script], &[]);
    let names = |calls: &[Vec<String>]| -> Vec<Vec<String>> {
        calls
            .iter()
            .map(|c| {
                c.iter()
                    .map(|a| Path::new(a).file_name().map_or(a.clone(), |n| n.to_string_lossy().into_owned()))
                    .collect()
            })
            .collect()
    };
    assert_eq!(names(&pod_merge), names(&slurm_merge));
    let parts: Vec<String> = (0..tasks).map(|k| format!("part-{k}.exr")).collect();
    let mut merged: Vec<String> = names(&slurm_merge)[0][1..=tasks as usize].to_vec();
    merged.sort();
    let mut expected = parts.clone();
    expected.sort();
    assert_eq!(merged, expected, "every part and no checkpoint");
    assert_eq!(merge_job.at("kind").text(), "Job");
}
