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
    lines = report._with_run_notes(merged, ["## 5. Memory", "", "text",
                                            "## 6. Time to the first image"])
    assert lines[:3] == ["## 5. Memory", "", f"*From run 1 (commit `{'a' * 10}`).*"]
    assert lines[-1] == f"*From run 2 (commit `{'b' * 10}`).*"
    # a study of one run says nothing of runs
    assert report._with_run_notes(_run(["memory"], "c" * 40), ["## 5. Memory"]) == ["## 5. Memory"]


def test_read_results_of_a_missing_file(tmp_path):
    assert study.read_results(str(tmp_path / "none.json")) is None
