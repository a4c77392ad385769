#!/usr/bin/env bash
# Times the README's test command as a newcomer meets it: a fresh clone of this checkout's HEAD
# (no target/, no virtual environment) in a temporary folder, `bash tests/all.sh` run there with
# CI's pinned property-test seed. Writes report/data/test_command.json: each step's seconds as
# all.sh printed them, the whole command's wall time, and where, when and on what it ran. Then
# `cargo run --release -p isolab-experiments --bin report -- --assemble-only` puts the times in
# README.md. Run it on an otherwise idle machine: the times are the machine's as much as ours.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
commit="$(git -C "$root" rev-parse HEAD)"
git clone --quiet --no-local "$root" "$work/isolab"
git -C "$work/isolab" checkout --quiet "$commit"
date_utc="$(date -u +%Y-%m-%dT%H:%M:%SZ)"
start=$(date +%s.%N)
(cd "$work/isolab" && PROPTEST_RNG_SEED=20261122 bash tests/all.sh) 2>&1 | tee "$work/log.txt"
end=$(date +%s.%N)
python3 - "$work/log.txt" "$root/report/data/test_command.json" "$commit" "$date_utc" "$start" "$end" <<'EOF'
import json, os, platform, re, subprocess, sys
log, out, commit, date_utc, start, end = sys.argv[1:]
steps = []
for line in open(log, encoding="utf-8", errors="replace"):
    m = re.match(r"^   \((.+): (\d+) s\)$", line.rstrip("\n"))
    if m and m.group(1) != "done":
        # "Python package: build into target/python-venv" -> "Python package"
        name = re.split(r" \(|:", m.group(1))[0]
        steps.append([name, float(m.group(2))])
def first(path, key):
    try:
        for line in open(path):
            if line.startswith(key):
                return line.split(":", 1)[1].strip() if ":" in line else line.split("=", 1)[1].strip().strip('"')
    except OSError:
        pass
    return "unknown"
def run(*cmd):
    try:
        return subprocess.run(cmd, capture_output=True, text=True, check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return "unknown"
root = os.path.dirname(os.path.dirname(os.path.dirname(out)))
memory = first("/proc/meminfo", "MemTotal")
record = {
    "provenance": {
        "experiment": "test_command",
        "commit": commit,
        # A clone of the commit is what ran, whatever this checkout holds beside it.
        "dirty": False,
        "date_utc": date_utc,
        "seconds": round(float(end) - float(start), 1),
        "cpu": first("/proc/cpuinfo", "model name"),
        "cores": os.cpu_count(),
        "memory_gib": round(int(memory.split()[0]) / 1024 / 1024, 2) if memory != "unknown" else 0.0,
        "os": f"{first('/etc/os-release', 'PRETTY_NAME')}, kernel {platform.release()}",
        "rustc": run("rustc", "--version"),
        "python": run("python3", "--version"),
        "isolab": re.search(r'^version = "([^"]+)"', open(os.path.join(root, "Cargo.toml")).read(), re.M).group(1),
        "command": "bash tests/time_fresh_clone.sh",
    },
    "steps": steps,
    "total_seconds": round(float(end) - float(start), 1),
}
os.makedirs(os.path.dirname(out), exist_ok=True)
with open(out + ".tmp", "w") as f:
    json.dump(record, f, indent=2)
    f.write("\n")
os.replace(out + ".tmp", out)
print(f"wrote {out}: {record['total_seconds']:.0f} s in all, steps {steps}")
EOF
