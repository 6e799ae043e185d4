"""`recolor BODY COLOUR rgb=(r, g, b)` in a layout: the body's colour word and rgb there and in
the layouts derived from it (spec.Layout.colours), checked where the operation is written: the
colour word and rgb as a body's are, a colour word the body does not have yet, and no look-alike
(observation.misnamed_twin: another body, or the body as it looked until then) called otherwise,
as the loader checks the scene's bodies."""

from __future__ import annotations

from robofollow.compiler.authoring.spec_checks import Checks
from robofollow.compiler.authoring.spec_syntax import LayoutOp
from robofollow.compiler.scene.observation import misnamed_twin
from robofollow.compiler.scene.spec import RGB_RANGE, Body, Colour, shown


def recolour(checks: Checks, op: LayoutOp, bodies: dict[str, Body], broken: set[str],
             colours: dict[str, Colour]) -> bool:
    """Give the body its new colour in `colours` (by body); False (reported) when it fails.
    Bodies in `broken` (a bad attribute, reported there) are left out of the look-alike
    check."""
    name = str(op.body)
    color, rgb = checks.colour(op.colour), checks.numbers(op.rgb, 3, RGB_RANGE)
    if color is None or rgb is None:
        return False
    body = shown(bodies[name], colours)
    if color == body.color:
        checks.error("same-colour", f"{name} is already {color} in this layout", op.colour)
        return False
    colour = Colour(color=color, rgb=rgb)
    # its look until now is a look-alike too: a new word needs a look a camera tells apart
    others = [body, *(shown(other, colours) for other in bodies.values()
                      if other.id != name and other.id not in broken)]
    twin = None if name in broken else misnamed_twin(shown(body, {name: colour}), others)
    if twin is not None:
        before = " did" if twin.id == name else ""
        checks.error("colour-mismatch", f"{name} recoloured {color} looks the same as "
                     f"{twin.id}{before} (kind, size, rgb), which is called {twin.color}",
                     op.colour)
        return False
    colours[name] = colour
    return True
