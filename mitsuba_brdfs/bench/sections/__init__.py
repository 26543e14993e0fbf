"""The sections of the performance study: one table, ``SECTIONS``, in running order.

Each ``Section`` says how its part is measured (``measure``: a function of a ``bench``
module, ``steps``: its progress steps, from its text module or, where they depend on what
the measurement does, from the measurement's) and how it is written into ``performance.md``
(``number`` and ``title``: its heading; ``text``: the lines under it; ``summary``: its
lines of the document's summary; ``plots``: its plot files and the functions that draw
them; ``recompiled``: its timed renders that had to be timed again). Adding a section to
the study is adding one entry here: ``bench --sections``, the study's results, its
document and its progress all follow this table.

The modules of this package write the sections' parts of the document (``format`` holds
what they share); the measurements are in the modules of ``bench``.
"""
import dataclasses
import importlib
from typing import Callable, Optional

from . import (accuracy, cpp, effects, energy, error, explore, figures_command, measured,
               memory, optimisation, startup, to_rgl)

__all__ = ["Section", "SECTIONS", "KEYS", "section", "numbers"]


def _none(data):
    """No renders timed again (sections that do not count them)."""
    return 0


@dataclasses.dataclass(frozen=True)
class Section:
    """One part of the study (see the package docstring)."""
    #: the name of its results (``results[key]``) and of ``bench --sections``
    key: str
    #: its number in the document; a ``subsection`` shares the number of the one before
    number: int
    #: its heading, also shown beside the progress bar
    title: str
    #: ``"module:function"`` of ``bench``, called as f(settings, available, progress) -> dict
    measure: str
    #: steps(settings) -> how many steps its progress bar counts
    steps: Callable
    #: text(data, document) -> the Markdown lines under its heading (data = results[key])
    text: Callable
    #: summary(data, document) -> lines of the summary: "- " bullets, then lines (a table)
    #: that follow the list
    summary: Optional[Callable] = None
    #: (file name in perf/, plot(data, path) -> True when it was drawn), ...
    plots: tuple = ()
    #: recompiled(data) -> timed renders that were timed again (a kernel was compiled)
    recompiled: Callable = _none
    #: a subsection (### heading, no number of its own)
    subsection: bool = False

    def run(self, settings, available, progress):
        """Measure the section; returns its results (JSON-ready)."""
        module, function = self.measure.split(":")
        module = importlib.import_module(f"{__package__.rpartition('.')[0]}.{module}")
        return getattr(module, function)(settings, available, progress)

    def heading(self):
        """The Markdown heading of the section."""
        return f"### {self.title}" if self.subsection else f"## {self.number}. {self.title}"


SECTIONS = (
    Section("error", 1, "Error against time", "error:run", error.steps, error.text,
            error.summary, (("error_vs_time.png", error.plot),), error.recompiled),
    Section("cpp", 2, "Speed against Mitsuba's C++ plugins", "speed:run_cpp", cpp.steps,
            cpp.text, cpp.summary, (("speed_vs_cpp.png", cpp.plot),), cpp.recompiled),
    Section("accuracy", 3, "The price of accuracy choices", "accuracy:run", accuracy.steps,
            accuracy.text, accuracy.summary, (("stable_vs_naive.png", accuracy.plot),),
            accuracy.recompiled),
    Section("effects", 4, "Only the effects a scene calls for", "speed:run_effects",
            effects.steps, effects.text, effects.summary, (("effects.png", effects.plot),),
            effects.recompiled),
    Section("figures", 4, "`direct` against `path` on the figure scenes", "speed:run_figures",
            effects.figures_steps, effects.figures_text, recompiled=effects.figures_recompiled,
            subsection=True),
    Section("memory", 5, "Memory", "memory:run", memory.steps, memory.text, memory.summary,
            (("memory.png", memory.plot),)),
    Section("startup", 6, "Time to the first image", "startup:run", startup.steps,
            startup.text, startup.summary, (("startup.png", startup.plot),)),
    Section("optimisation", 7, "Optimisation loops, traced and frozen", "optimisation:run",
            optimisation.steps, optimisation.text, optimisation.summary),
    Section("figures_command", 8, "The figures command", "startup:run_figures_command",
            figures_command.steps, figures_command.text, figures_command.summary),
    Section("explore", 9, "The explorer: a parameter change redrawn", "explore:run",
            explore.steps, explore.text, explore.summary),
    Section("measured", 10, "Fitting a measured material", "measured:run", measured.steps,
            measured.text, measured.summary),
    Section("to_rgl", 11, "Writing a measured material as an RGL file", "to_rgl:run",
            to_rgl.steps, to_rgl.text, to_rgl.summary),
    Section("energy", 12, "Energy compensation: accuracy against time", "energy:run",
            energy.steps, energy.text, energy.summary,
            (("energy_error_vs_time.png", energy.plot),), energy.recompiled),
)

#: the sections' keys, in running order
KEYS = tuple(s.key for s in SECTIONS)


def section(key):
    """The section of ``key``."""
    return next(s for s in SECTIONS if s.key == key)


def numbers():
    """Section key -> its number in the document."""
    return {s.key: s.number for s in SECTIONS}
