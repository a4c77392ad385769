"""README.md's quick starts run as written: the Python block in a fresh folder, and the command
line's block with the binary the Rust tests built (ISOLAB_CLI), from a folder holding the shipped
models as a clone does."""

import os
import re
import subprocess
from pathlib import Path

import pytest

README = Path(__file__).resolve().parents[2] / "README.md"


def blocks(language, readme=README):
    return re.findall(r"```" + language + r"\n(.*?)```", readme.read_text(), re.S)


def test_the_python_quick_start_runs(tmp_path, monkeypatch, capsys):
    [code] = blocks("python")
    monkeypatch.chdir(tmp_path)
    exec(compile(code, "README.md", "exec"), {})
    assert capsys.readouterr().out.startswith("True "), "the quick start's mesh is not closed"
    assert (tmp_path / "ball.glb").stat().st_size > 0


def test_the_package_readme_example_runs(tmp_path, monkeypatch):
    """python/README.md, the package's description on an index."""
    [code] = blocks("python", README.parent / "python" / "README.md")
    monkeypatch.chdir(tmp_path)
    exec(compile(code, "python/README.md", "exec"), {})
    assert (tmp_path / "ball.glb").stat().st_size > 0


def test_the_command_line_quick_start_runs(tmp_path):
    cli = os.environ.get("ISOLAB_CLI")
    if not cli:
        pytest.fail("ISOLAB_CLI names the isolab binary (tests/all.sh sets it)")
    (tmp_path / "models").symlink_to(README.parent / "models")
    lines = [l for b in blocks("sh") for l in b.splitlines() if l.startswith("./target/release/isolab ")]
    assert len(lines) >= 4, lines
    for line in lines:
        args = line.split("#")[0].split()[1:]
        run = subprocess.run([cli, *args], cwd=tmp_path, capture_output=True, text=True, timeout=300)
        assert run.returncode == 0, f"{line}: {run.stderr}"
    for made in ["sphere.obj", "sphere.json", "bunny.ply", "bunny.png"]:
        assert (tmp_path / made).stat().st_size > 0, made
