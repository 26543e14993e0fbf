"""Check the relative links of the repository's Markdown: README.md and docs/**/*.md.

Every link that is not a URL must name a file or folder that exists, and a ``#anchor`` must
be a heading of the target page (GitHub's rule: lower case, punctuation dropped, spaces as
dashes), and one heading only (a link to a heading repeated on its page lands on the first
copy). Prints each broken link and exits with status 1 if there is one.

    python scripts/check_links.py
"""
import glob
import os
import re
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
LINK = re.compile(r"!?\[[^\]]*\]\(([^)\s]+)\)")
FENCE = re.compile(r"^```.*?^```", re.S | re.M)


def slug(heading):
    """GitHub's anchor of a heading."""
    text = re.sub(r"[^\w\- ]", "", heading.strip().lower())
    return text.replace(" ", "-")


def headings(path):
    """{anchor: how many headings of the file have it} (GitHub gives a repeated heading's
    second and later copies -1, -2, ... too)."""
    seen = {}
    text = FENCE.sub("", open(path, encoding="utf-8").read())
    for line in text.splitlines():
        m = re.match(r"^#{1,6}\s+(.*)$", line)
        if m:
            s = slug(m.group(1))
            seen[s] = seen.get(s, 0) + 1
    return seen


def anchors(path):
    """The anchors of a Markdown file's headings (a repeated heading gets -1, -2, ...)."""
    out = set()
    for s, n in headings(path).items():
        out |= {s} | {f"{s}-{k}" for k in range(1, n)}
    return out


def broken(path):
    """The broken relative links of one Markdown file."""
    text = FENCE.sub("", open(path, encoding="utf-8").read())
    text = re.sub(r"`[^`\n]*`", "", text)  # inline code is not a link
    bad = []
    for target in LINK.findall(text):
        if re.match(r"^[a-z]+:", target):
            continue  # a URL
        file, _, anchor = target.partition("#")
        full = os.path.normpath(os.path.join(os.path.dirname(path), file)) if file else path
        if not os.path.exists(full):
            bad.append(f"{target}: no such file")
        elif anchor and full.endswith(".md") and anchor not in anchors(full):
            bad.append(f"{target}: no heading #{anchor}")
        elif anchor and full.endswith(".md") and headings(full).get(anchor, 0) > 1:
            bad.append(f"{target}: {headings(full)[anchor]} headings of that name (the link "
                       f"lands on the first)")
    return bad


def main():
    files = [os.path.join(ROOT, "README.md")] + sorted(
        glob.glob(os.path.join(ROOT, "docs", "**", "*.md"), recursive=True))
    errors = [(f, b) for f in files for b in broken(f)]
    for f, b in errors:
        print(f"{os.path.relpath(f, ROOT)}: {b}")
    print(f"{len(files)} files, {len(errors)} broken link(s)")
    return 1 if errors else 0


if __name__ == "__main__":
    sys.exit(main())
