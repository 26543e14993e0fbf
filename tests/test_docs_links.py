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
    """The checker itself fails on a link to a missing file and on one to a heading its page
    repeats (run on a copy of its folder)."""
    import shutil
    (tmp_path / "scripts").mkdir()
    shutil.copy(os.path.join(ROOT, "scripts", "check_links.py"), tmp_path / "scripts")
    (tmp_path / "docs").mkdir()
    (tmp_path / "docs" / "page.md").write_text("# Page\n\n## Same\n\ntext\n\n## Same\n")
    (tmp_path / "README.md").write_text("# Title\n\n[gone](docs/missing.md) [ok](#title) "
                                        "[twice](docs/page.md#same) [second](docs/page.md#same-1)\n")
    r = subprocess.run([sys.executable, str(tmp_path / "scripts" / "check_links.py")],
                       capture_output=True, text=True)
    assert r.returncode == 1 and "missing.md" in r.stdout + r.stderr
    # a link to a heading repeated on its page lands on the first copy: refused
    assert "docs/page.md#same: 2 headings of that name" in r.stdout
    assert "#same-1" not in r.stdout and "2 broken link(s)" in r.stdout, r.stdout
