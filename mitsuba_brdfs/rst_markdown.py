"""The RST of the models' docstrings as Markdown, for the plugin reference (``manual``):
paragraphs, lists, simple tables and literal blocks, and the XML and Python examples set
apart.
"""
import re

from .docstrings import BORDER, blocks, indent, parse_table

__all__ = ["inline", "rst_to_markdown"]


def inline(text):
    """RST inline literals as Markdown code, with table pipes escaped."""
    return re.sub(r"``(.+?)``", r"`\1`", text).replace("|", "\\|")


def _md_table(header, rows, pad=""):
    header = header or [""] * len(rows[0])
    lines = ["| " + " | ".join(inline(c) for c in header) + " |",
             "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(inline(c) for c in r) + " |" for r in rows]
    return [pad + ln for ln in lines]


def _fence(block, pad, lang="text"):
    cut = indent(block)
    return [pad + "```" + lang] + [pad + ln[cut:] for ln in block] + [pad + "```"]


def _paragraph(block):
    out, is_list = [], block[0].startswith(("- ", "  "))  # a list, or a list item's tail
    for i, line in enumerate(block):
        body = line.lstrip()
        lead = line[:len(line) - len(body)]
        # a wrapped line must not start a Markdown list, heading or quote (list items may)
        item = is_list and not lead and body.startswith("- ")
        if i and not item and re.match(r"([-+*#>]|\d+[.)])(\s|$)", body):
            body = "\\" + body
        out.append(lead + re.sub(r"``(.+?)``", r"`\1`", body))
    out[-1] = re.sub(r"\s*::$", ":", out[-1]) if not out[-1].endswith(" ::") else out[-1][:-3]
    return out


def rst_to_markdown(lines):
    """The docstring's prose as Markdown, and its XML and Python examples."""
    md, examples, pad, literal = [], {}, "", False
    for block in blocks(lines):
        text = " ".join(ln.strip() for ln in block)
        if literal and indent(block) > 0 and literal in ("XML", "Python"):
            examples[literal] = "\n".join(ln[indent(block):] for ln in block)
            literal = False
            continue
        m = re.match(r"^(XML|Python)::$", text) or re.match(r"^(Python):\s*``(.+)``$", text)
        if m:
            if m.lastindex == 2:
                examples["Python"] = m.group(2)
            literal = m.group(1) if m.lastindex == 1 else False
            continue
        if BORDER.match(block[0]):
            md += _md_table(*parse_table(block), pad=pad)
        elif indent(block) > len(pad) or literal:
            md += _fence(block, pad, "xml" if block[0].lstrip().startswith("<") else "text")
        else:
            if indent(block) == 0:  # inside a list item when its last item line says so
                pad = "  " if [ln for ln in block if ln[0] != " "][-1].startswith("- ") else ""
            md += _paragraph(block)
        literal = block[-1].rstrip().endswith("::")
        md.append("")
    return md, examples
