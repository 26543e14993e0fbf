"""Relations between a model's parameters, declared once.

A model lists its relations in ``RELATIONS`` (a class attribute); three readers use them:
the parameter reader refuses what breaks one (``check``: at load, one line naming the
plugin, the parameter and the rule, as every refused value), the manual states them
under the parameter table (``describe``), and the explorer's controls follow them
(``partners`` and ``alternatives``: a partner is sent along with the parameter changed, an
alternative is taken out of the dictionary when it is set).

The kinds:

- ``Together(a, b)``: both or neither (``alpha_u`` and ``alpha_v``; the lecture's A and B);
- ``Excludes(first, second)``: two ways of giving the same thing: none of ``first`` when
  one of ``second`` is given (Phong exponents or a roughness; a ramp or its two bands);
  with ``every=True`` only when all of ``second`` are;
- ``Only(names, option, value)``: these parameters with that value of a load-time option
  alone (EON's ``roughness`` with ``form = energy_preserving``);
- ``Absent(names)``: never given to this model (an anisotropic roughness of an isotropic
  lobe), with the reason.

Each relation carries ``why``, the reason a user reads in the message and the manual.
"""

__all__ = ["Together", "Excludes", "Only", "Absent", "check", "describe", "partners",
           "alternatives", "companions"]


def _q(name):
    return f"``{name}``"


def _given(props, names):
    return [n for n in names if n in props]


class Together:
    """``names``: given both (all) or neither."""

    def __init__(self, *names, why):
        self.names, self.why = names, why

    def check(self, r, options):
        given = _given(r.props, self.names)
        if given and len(given) < len(self.names):
            missing = next(n for n in self.names if n not in given)
            raise r.error(missing, f"given with '{given[0]}' ({self.why})", "nothing")

    def describe(self):
        return f"{' and '.join(map(_q, self.names))}: both or neither."


class Excludes:
    """None of ``first`` when one of ``second`` (with ``every``: all of them) is given."""

    def __init__(self, first, second, why, every=False):
        self.first, self.second, self.why, self.every = tuple(first), tuple(second), why, every

    def check(self, r, options):
        culprit = _given(r.props, self.first)
        other = _given(r.props, self.second)
        if not culprit or not other or (self.every and len(other) < len(self.second)):
            return
        when = (" and ".join(f"'{n}'" for n in self.second) + " are" if self.every else
                f"'{other[0]}' is")
        raise r.error(culprit[0], f"absent when {when} given ({self.why})",
                      f"'{culprit[0]}' and '{other[0]}'")

    def describe(self):
        a = ", ".join(map(_q, self.first))
        b = (" and ".join if self.every else " or ".join)(map(_q, self.second))
        return f"{a}: not with {b} ({self.why})."


class Only:
    """``names`` only when the load-time option ``option`` is ``value``."""

    def __init__(self, names, option, value, why, default=None):
        self.names, self.option, self.value, self.why = tuple(names), option, value, why
        self.default = default

    def check(self, r, options):
        value = r.props.get(self.option, self.default)
        if value == self.value or value not in options.get(self.option, (value,)):
            return  # (a value the option does not take: its reader refuses it)
        for n in _given(r.props, self.names):
            raise r.error(n, f"given only with {self.option} '{self.value}' ({self.why})",
                          f"{self.option} '{value}'")

    def describe(self):
        return (f"{', '.join(map(_q, self.names))}: only with {_q(self.option)} = "
                f"``{self.value}`` ({self.why}).")


class Absent:
    """``names`` are never given to this model."""

    def __init__(self, names, why):
        self.names, self.why = tuple(names), why

    def check(self, r, options):
        for n in _given(r.props, self.names):
            raise r.error(n, f"absent: {self.why}", repr(r.props.get(n)))

    def describe(self):
        return f"{', '.join(map(_q, self.names))}: not taken ({self.why})."


def check(r, relations, options):
    """Raise ``r.error`` for the first relation the given properties break (``options``:
    the model's load-time options and their values, ``OPTIONS``)."""
    for rel in relations:
        rel.check(r, options)


def describe(relations):
    """The manual's sentences, one per relation."""
    return [rel.describe() for rel in relations]


def partners(relations, name):
    """The parameters that come with ``name`` (``Together``)."""
    return [n for rel in relations if isinstance(rel, Together) and name in rel.names
            for n in rel.names if n != name]


def alternatives(relations, name):
    """The parameters that setting ``name`` takes out (``Excludes``, both ways; a partner's
    alternatives are its partners' too)."""
    def direct(n):
        out = set()
        for rel in relations:
            # (one of several that exclude together takes nothing out alone)
            if isinstance(rel, Excludes) and not rel.every:
                if n in rel.first:
                    out |= set(rel.second)
                if n in rel.second:
                    out |= set(rel.first)
        return out
    out = direct(name)
    for p in partners(relations, name):
        out |= direct(p)
    return sorted(out - {name})


def companions(relations, name, defaults):
    """The settings ``name`` loads with, at least: its partners and the option value it
    needs (``defaults``: a value for each parameter)."""
    out = {p: defaults[p] for p in partners(relations, name)}
    for rel in relations:
        if isinstance(rel, Only) and name in rel.names:
            out[rel.option] = rel.value
    return out
