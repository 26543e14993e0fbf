"""What a check of the suite returns, and how results read: ``Result``, the ``warning``
records of what Mitsuba's integrators mask, ``verdict`` (FAIL, WARN or PASS from problems and
warnings), ``summary`` (one BSDF's verdict line), ``bsdf_record`` (one BSDF's results as
``check --json`` writes them), and the small formatters the checks' messages share. The statuses are described in ``validate.suite``.
"""
from dataclasses import dataclass, field

import mitsuba as mi

__all__ = ["Result", "warning", "verdict", "summary", "bsdf_record", "flag_names", "fmt",
           "deg"]


@dataclass
class Result:
    """What one check found: ``status`` is PASS, WARN, FAIL, NOTE or SKIP; ``numbers`` what
    it measured (plain numbers, lists and strings, as JSON holds them); ``message`` one line
    saying what they mean; ``warnings`` what Mitsuba's integrators mask (one record per
    kind: ``what``, ``count``, ``example``); ``data`` arrays for plots."""
    name: str
    status: str
    numbers: dict = field(default_factory=dict)
    message: str = ""
    data: dict = field(default_factory=dict, repr=False)
    warnings: list = field(default_factory=list)

    @property
    def passed(self):
        return self.status != "FAIL"

    def as_dict(self):
        return {"name": self.name, "status": self.status, "passed": self.passed,
                "numbers": self.numbers, "message": self.message, "warnings": self.warnings}


def warning(what, count, example):
    """A WARN record: what was found, how often, one example (where and its values)."""
    return {"what": what, "count": int(count), "example": example}


def verdict(name, numbers, message, problems=(), warnings=(), data=None):
    """FAIL when there are problems (strings), WARN when there are only warnings
    (``warning`` records), PASS otherwise; the message lists both."""
    problems, warnings = list(problems), list(warnings)
    if problems:
        message += "; " + "; ".join(problems)
    if warnings:
        message += "; masked by Mitsuba's integrators: " + "; ".join(
            f"{w['count']:,} x {w['what']} (e.g. {w['example']})" for w in warnings)
    status = "FAIL" if problems else "WARN" if warnings else "PASS"
    return Result(name, status, numbers, message, data or {}, warnings)


def summary(results, strict=False):
    """(passed, line): the verdict of one BSDF's results, e.g. ``PASS (10 checks; 2 warned:
    hard_cases, flags; 1 skipped)`` or ``FAIL (2 of 10 checks failed: chi2, flags)``: the
    checks that failed and those that warned, each named, as many as their lines; a SKIP
    is not counted as a check, but said; with strict, a warning fails."""
    checked = [r for r in results if r.status != "SKIP"]
    failed = [r.name for r in checked if r.status == "FAIL"]
    warned = [r.name for r in checked if r.status == "WARN"]
    if strict and warned:
        failed += [f"{w} (warning, --strict)" for w in warned]
        warned = []
    extra = [f"{len(warned)} warned: {', '.join(warned)}"] if warned else []
    skipped = len(results) - len(checked)
    if skipped:
        extra.append(f"{skipped} skipped")
    if failed:
        line = f"FAIL ({len(failed)} of {_count(len(checked), 'check')} failed: {', '.join(failed)}"
        return False, line + (f"; {'; '.join(extra)})" if extra else ")")
    return True, f"PASS ({'; '.join([_count(len(checked), 'check')] + extra)})"


def bsdf_record(name, results, seconds, strict=False):
    """What ``check --json`` says of one BSDF (the explorer's check says the same): its
    ``name``, its ``checks`` (``Result.as_dict``), the ``seconds`` they took, whether it
    ``passed`` and its ``verdict`` line (``summary``), and how many ``warnings`` records
    its WARN checks hold together (a check may warn of several things)."""
    passed, line = summary(results, strict)
    return {"name": name, "checks": [r.as_dict() for r in results],
            "seconds": round(seconds, 2), "passed": passed, "verdict": line,
            "warnings": sum(len(r.warnings) for r in results)}


def _count(n, word):
    """``1 check``, ``2 checks``."""
    return f"{n:,} {word}{'s' * (n != 1)}"


def flag_names(flags):
    """BSDF flags as text: ``GlossyReflection|FrontSide``, or ``Empty``."""
    names = [f.name for f in mi.BSDFFlags if f.value and (f.value & (f.value - 1)) == 0
             and flags & f.value]
    return "|".join(names) or "Empty"


def fmt(x, digits=4):
    """A number with ``digits`` significant digits."""
    return f"{x:.{digits}g}"


def deg(t):
    """An incidence in degrees, as short as it goes: 0, 89.9."""
    return f"{t:g}"
