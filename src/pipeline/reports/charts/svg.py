"""A :class:`~.scene.Scene` as SVG: paths, markers (one path per series), text in the
report's font, clipped groups; coordinates in points to 0.1 pt."""

from __future__ import annotations

from html import escape

from pipeline.reports.charts.fixed import path_texts, rows
from pipeline.reports.charts.scene import (
    Group,
    Label,
    Marks,
    Path,
    Scene,
    outline,
    outline_runs,
    paths,
)
from pipeline.reports.web_fonts import FAMILY

FONT = f"{FAMILY}, DejaVu Sans, Verdana, Arial, sans-serif"
"""The chart text's font: the one the HTML report embeds (:mod:`~pipeline.reports.web_fonts`),
then an installed DejaVu Sans (a standalone SVG), then look-alikes."""


def _n(value: float) -> str:
    out = f"{value:.1f}"
    out = out[:-2] if out.endswith(".0") else out
    return "0" if out == "-0" else out


POINT = "{},{} "
"""A path's point in its ``d`` (:func:`~.fixed.path_texts`' template)."""


def _path(p: Path, texts: dict[int, list[str]]) -> str:
    """``p`` as a ``path`` element, its subpaths' points written in ``texts``
    (:func:`~.fixed.path_texts` of :data:`POINT`)."""
    close = "Z" if p.closed else ""
    d = "".join(f"M{text[:-1].replace(' ', 'L', 1)}{close}" for text in texts[id(p)])
    attrs = [f'd="{d}"', f'fill="{p.fill or "none"}"']
    if p.stroke is not None:
        attrs.append(f'stroke="{p.stroke.colour}" stroke-width="{p.stroke.width:g}"')
        if p.stroke.dash:
            attrs.append(f'stroke-dasharray="{" ".join(f"{d:g}" for d in p.stroke.dash)}"')
    return f"<path {' '.join(attrs)}/>"


def _marks(m: Marks) -> str:
    if not len(m.xy):
        return ""
    shape = outline(m.shape, m.size)
    if shape is None:
        r = m.size / 2 if m.shape != "." else m.size / 4
        arcs = f"a{r:.2f},{r:.2f} 0 1,0 {2 * r:.2f},0a{r:.2f},{r:.2f} 0 1,0 {-2 * r:.2f},0"
        d = rows(f"M{{}},{{}}{arcs}", m.xy - [r, 0.0], 1)
        closed = True
    else:
        offsets, closed = shape
        runs = outline_runs(m.xy, offsets, closed)
        d = "".join(
            "Z" if v is None else f"{'M' if v[2] else 'L'}{_n(v[0])},{_n(v[1])}" for v in runs
        )
    if m.hollow or not closed:
        return f'<path d="{d}" fill="none" stroke="{m.colour}" stroke-width="{m.edge:g}"/>'
    return f'<path d="{d}" fill="{m.colour}"/>'


def _label(t: Label) -> str:
    attrs = [f'x="{_n(t.x)}"', f'y="{_n(t.y)}"', f'font-size="{t.size:g}"', f'fill="{t.colour}"']
    if t.anchor != "start":
        attrs.append(f'text-anchor="{t.anchor}"')
    if t.bold:
        attrs.append('font-weight="bold"')
    if t.angle:
        attrs.append(f'transform="rotate({-t.angle} {_n(t.x)} {_n(t.y)})"')
    box = ""
    if t.box:
        x0, y0, x1, y1 = t.extent()
        box = (
            f'<rect x="{_n(x0 - 1.5)}" y="{_n(y0 - 1)}" width="{_n(x1 - x0 + 3)}" '
            f'height="{_n(y1 - y0 + 2)}" fill="#ffffff"/>'
        )
    return f"{box}<text {' '.join(attrs)}>{escape(t.text, quote=False)}</text>"


def _group(g: Group, prefix: str, clips: list[int], texts: dict[int, list[str]]) -> str:
    body = "".join(
        _group(i, prefix, clips, texts)
        if isinstance(i, Group)
        else _path(i, texts)
        if isinstance(i, Path)
        else _marks(i)
        if isinstance(i, Marks)
        else _label(i)
        for i in g.items
    )
    attrs = (f' id="{escape(g.id)}"' if g.id else "") + (f' class="{g.kind}"' if g.kind else "")
    if g.clip is not None:
        clips.append(len(clips))
        name = f"{prefix}clip{len(clips)}"
        x, y, w, h = g.clip
        body = (
            f'<clipPath id="{name}"><rect x="{_n(x)}" y="{_n(y)}" width="{_n(w)}" '
            f'height="{_n(h)}"/></clipPath><g clip-path="url(#{name})">{body}</g>'
        )
    if not attrs and g.clip is None:
        return body
    return f"<g{attrs}>{body}</g>"


def to_svg(scene: Scene, id_prefix: str = "", title: str = "", style: str = "") -> str:
    """``scene`` as a standalone SVG element (clip-path ids start with ``id_prefix``, so
    several SVGs can share one HTML page; ``title``: its accessible name; ``style``: CSS
    of its own, e.g. the embedded fonts of a file saved alone)."""
    w, h = _n(scene.width), _n(scene.height)
    named = f"<title>{escape(title, quote=False)}</title>" if title else ""
    styled = f"<style>{style}</style>" if style else ""
    return (
        f'<svg xmlns="http://www.w3.org/2000/svg" width="{w}pt" height="{h}pt" '
        f'viewBox="0 0 {w} {h}" font-family="{FONT}" stroke-linejoin="round" role="img">'
        f'{named}{styled}<rect width="{w}" height="{h}" fill="#ffffff"/>'
        f"{_group(scene.root, id_prefix, [], path_texts(paths(scene.root), POINT, 1))}</svg>"
    )
