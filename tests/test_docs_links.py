"""The repository's Markdown (README.md, docs/) links only to files and headings that exist."""
import os
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def test_relative_links_resolve():
    r = subprocess.run([sys.executable, os.path.join(ROOT, "scripts", "check_links.py")],
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stdout + r.stderr
    assert " 0 broken link(s)" in r.stdout


def test_a_broken_link_is_found(tmp_path):
    """The checker itself fails on a link to a missing file (run on a copy of its folder)."""
    import shutil
    (tmp_path / "scripts").mkdir()
    shutil.copy(os.path.join(ROOT, "scripts", "check_links.py"), tmp_path / "scripts")
    (tmp_path / "docs").mkdir()
    (tmp_path / "README.md").write_text("# Title\n\n[gone](docs/missing.md) [ok](#title)\n")
    r = subprocess.run([sys.executable, str(tmp_path / "scripts" / "check_links.py")],
                       capture_output=True, text=True)
    assert r.returncode == 1 and "missing.md" in r.stdout + r.stderr
