"""A compact, readable notation for logical forms (what `robofollow parse` prints).

    pick(left, block[right_of(sphere[red])])
    place(right, slab[red] -> on(label[blue]), via slab[yellow], short side facing front)
    if exists object[in(bowl)]: pick(left, sphere[blue]) otherwise: place(...)
"""

from __future__ import annotations

from robofollow.compiler.language import lf

_ORDINALS = {1: "1st", 2: "2nd", 3: "3rd", 4: "4th", 5: "5th"}


def constraint(c: lf.Constraint) -> str:
    if isinstance(c, lf.ColorIs):
        text = c.color
    elif isinstance(c, lf.SizeIs):
        return c.size
    elif isinstance(c, lf.ExtremeIs):
        text = c.extreme
    elif isinstance(c, lf.NotKind):
        return f"not {c.noun}"
    elif isinstance(c, lf.OrdinalIs):
        return f"{_ORDINALS[c.rank]} from the {c.side}"
    elif isinstance(c, lf.MiddleIs):
        return "middle"
    elif isinstance(c, lf.Between):
        text = f"between({', '.join(ref(landmark) for landmark in c.landmarks)})"
    elif isinstance(c, lf.NearestIs):
        text = f"{c.nearness}({ref(c.landmark)})"
    else:
        text = f"{c.relation}({ref(c.landmark)})"
    return f"not {text}" if c.negated else text


def ref(r: lf.Ref) -> str:
    if not r.constraints:
        return r.noun
    return f"{r.noun}[{', '.join(constraint(c) for c in r.constraints)}]"


def command(c: lf.Pick | lf.Place | lf.Push) -> str:
    parts = [c.arm or "any arm"]
    if isinstance(c, lf.Pick):
        parts.append(ref(c.object))
    elif isinstance(c, lf.Push):
        parts.append(f"{ref(c.object)} -> towards {ref(c.toward)}")
    else:
        destination = c.destination
        parts.append(f"{ref(c.object)} -> {destination.relation}({ref(destination.landmark)})")
        parts.extend(f"{w.mode} {ref(w.landmark)}" for w in c.route)
        if c.orientation is not None:
            parts.append(f"{c.orientation.side} side facing {c.orientation.facing}")
    return f"{c.type}({', '.join(parts)})"


def body(b: lf.Body) -> str:
    if isinstance(b, lf.Sequence):
        return "; then ".join(command(step) for step in b.steps)
    return command(b)


def condition(c: lf.Condition) -> str:
    if isinstance(c, lf.Exists):
        return f"{'not ' if c.negated else ''}exists {ref(c.ref)}"
    return f"{ref(c.subject)} is {constraint(c.property)}"


def notation(instruction: lf.Instruction) -> str:
    """One line that shows the whole logical form."""
    if isinstance(instruction, lf.Conditional):
        text = f"if {condition(instruction.condition)}: {body(instruction.then)}"
        if instruction.otherwise is not None:
            text += f" otherwise: {body(instruction.otherwise)}"
        return text
    return body(instruction)
