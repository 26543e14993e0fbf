"""The performance study's record of where its numbers come from."""
from mitsuba_brdfs.bench import study


def test_git_info_names_the_commit():
    g = study.git_info()
    assert len(g["commit"]) == 40 and g["date"]
    assert isinstance(g["dirty"], list)


MACHINE = {"cpu": "x", "cores": 2, "drjit_threads": 2, "mitsuba": "3", "drjit": "1", "llvm": "19",
           "python": "3", "variant": "llvm_ad_rgb"}


def _run(sections, commit, mode="full"):
    """A results dict as ``measure`` returns it, each section holding its own name."""
    return {"mode": mode, "sections": list(sections), "settings": {"mode": mode},
            "git": {"commit": commit, "date": "", "dirty": []}, "machine": MACHINE,
            "load_average_start": [0, 0, 0], "load_average_end": [0, 0, 0],
            "section_seconds": {s: 1.0 for s in sections}, "total_seconds": len(sections),
            **{s: {"from": commit} for s in sections}}


def test_merge_replaces_the_sections_run_again():
    old = _run(["error", "cpp", "memory"], "a" * 40)
    merged = study.merge(old, _run(["cpp", "startup"], "b" * 40))
    assert merged["sections"] == ["error", "cpp", "memory", "startup"]  # the study's order
    assert merged["error"] == {"from": "a" * 40} and merged["memory"] == {"from": "a" * 40}
    assert merged["cpp"] == {"from": "b" * 40} and merged["startup"] == {"from": "b" * 40}
    assert [r["sections"] for r in merged["runs"]] == [["error", "memory"], ["cpp", "startup"]]
    assert merged["total_seconds"] == 4
    # merged again: a run whose sections were all measured anew leaves the list
    again = study.merge(merged, _run(["error", "memory"], "c" * 40))
    assert [r["git"]["commit"][0] for r in again["runs"]] == ["b", "c"]
    # nothing to keep: a run of every section, another mode, no earlier study
    new = _run(["error", "cpp", "memory"], "d" * 40)
    assert study.merge(old, new) is new
    assert study.merge(old, _run(["cpp"], "e" * 40, mode="quick"))["mode"] == "quick"
    assert study.merge(None, new) is new


def test_a_merged_study_names_the_run_of_each_section():
    from mitsuba_brdfs.bench import report
    merged = study.merge(_run(["error", "memory"], "a" * 40), _run(["startup"], "b" * 40))
    header = "\n".join(report._header(merged))
    assert "in 2 runs" in header
    assert f"Run 1 (sections 1, 5) from commit `{'a' * 40}`" in header
    assert f"Run 2 (section 6) from commit `{'b' * 40}`" in header
    assert report._run_note(merged, "memory") == ["", f"*From run 1 (commit `{'a' * 10}`).*"]
    assert report._run_note(merged, "startup") == ["", f"*From run 2 (commit `{'b' * 10}`).*"]
    # a study of one run says nothing of runs
    assert report._run_note(_run(["memory"], "c" * 40), "memory") == []


def test_one_table_numbers_and_runs_the_sections():
    import importlib

    from mitsuba_brdfs.bench.sections import SECTIONS
    assert study.SECTIONS == tuple(s.key for s in SECTIONS)
    assert len(set(study.SECTIONS)) == len(SECTIONS)
    numbers = [s.number for s in SECTIONS]
    assert numbers == sorted(numbers) and numbers[0] == 1
    for before, s in zip(SECTIONS, SECTIONS[1:]):
        # a new number follows the last one; a subsection keeps its section's number
        assert s.number == before.number + (0 if s.subsection else 1), s.key
    for s in SECTIONS:
        assert s.heading().startswith("### " if s.subsection else f"## {s.number}. ")
        module, function = s.measure.split(":")
        assert callable(getattr(importlib.import_module(f"mitsuba_brdfs.bench.{module}"), function))
        assert s.steps(study.QUICK) > 0 and s.steps(study.FULL) >= s.steps(study.QUICK), s.key


def test_read_results_of_a_missing_file(tmp_path):
    assert study.read_results(str(tmp_path / "none.json")) is None
