"""One self-contained HTML page: sections, sortable tables, Vega-Lite charts, pictures, videos.

Nothing on the page is fetched from a network: the Vega, Vega-Lite and vega-embed bundle is
inlined (``vl_convert.javascript_bundle``, the bundle Altair inlines in its own
``save(inline=True)``), pictures are embedded as data URIs, and a video is a file of the run
folder referenced by a relative path. The few lines of JavaScript written here sort tables
and seek videos; every chart is drawn by Vega.
"""

from __future__ import annotations

import base64
import functools
import html
import json
import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import pandas as pd
import vl_convert

from occbench.io.write import write_atomic
from occbench.sources.cache import cache_root

BUNDLE_MARK = "window.vegaEmbed="  # vl-convert's bundle sets it: the kept copy is one
CSS = """
body{font-family:system-ui,-apple-system,'Segoe UI',Roboto,sans-serif;margin:0 auto;
max-width:1100px;padding:0 24px 48px;color:#222;line-height:1.45}
h1{font-size:1.6em;margin:24px 0 4px} h2{font-size:1.25em;margin:28px 0 8px;
border-bottom:1px solid #ddd;padding-bottom:4px} h3{font-size:1.05em;margin:18px 0 6px}
nav a{margin-right:14px} .note{color:#555;font-size:.92em}
table.sortable{border-collapse:collapse;font-size:.9em;margin:6px 0 12px}
table.sortable th,table.sortable td{border:1px solid #ddd;padding:3px 8px;text-align:right}
table.sortable th{background:#f3f3f3;cursor:pointer;user-select:none;position:sticky;top:0}
table.sortable th:hover{background:#e6eefc} table.sortable td.text{text-align:left}
td.best{font-weight:bold;background:#eef6ea} td.nd{color:#777}
pre{background:#f7f7f7;border:1px solid #e3e3e3;padding:8px;overflow:auto;font-size:.85em;
max-height:420px} img.plot{max-width:100%;border:1px solid #eee;margin:6px 0}
.player{position:sticky;top:0;background:#fff;z-index:2;padding:6px 0;
border-bottom:1px solid #eee} video{max-width:100%;max-height:360px;background:#000}
.frame{font-family:monospace;margin-left:8px} summary{cursor:pointer;font-weight:600;
margin:10px 0}
"""

SCRIPT = """
function sortTable(th){const table=th.closest('table');const i=[...th.parentNode.children]
.indexOf(th);const asc=th.dataset.order!=='asc';th.parentNode.querySelectorAll('th')
.forEach(h=>delete h.dataset.order);th.dataset.order=asc?'asc':'desc';const body=
table.tBodies[0];const rows=[...body.rows];const key=r=>{const t=r.cells[i].dataset.v??
r.cells[i].textContent;const n=parseFloat(t);return isNaN(n)?t:n};rows.sort((a,b)=>{const
x=key(a),y=key(b);const c=(typeof x==='number'&&typeof y==='number')?x-y:String(x)
.localeCompare(String(y));return asc?c:-c});rows.forEach(r=>body.appendChild(r))}
function videoOf(seq){return document.querySelector('video[data-sequence="'+seq+'"]')}
function frameTime(v,frame){return (frame-Number(v.dataset.first)+0.5)/Number(v.dataset.fps)}
function frameAt(v){return Number(v.dataset.first)+Math.floor(v.currentTime*Number(v.dataset.fps))}
function seek(seq,frame){const v=videoOf(seq);if(!v)return false;v.pause();
v.currentTime=frameTime(v,frame);v.closest('.player').scrollIntoView({block:'nearest'});
return true}
document.addEventListener('DOMContentLoaded',()=>{
document.querySelectorAll('video[data-sequence]').forEach(v=>{const out=document
.getElementById('frame-'+v.dataset.sequence);const show=()=>{if(out)out.textContent=
'frame '+frameAt(v)};v.addEventListener('timeupdate',show);v.addEventListener('seeked',show)});
document.querySelectorAll('.chart').forEach(el=>{const spec=JSON.parse(document
.getElementById(el.dataset.spec).textContent);vegaEmbed(el,spec,{actions:false,renderer:'svg'})
.then(r=>{el.dataset.ready='1';const seq=el.dataset.sequence;if(seq){r.view
.addEventListener('click',(e,item)=>{if(item&&item.datum&&item.datum.frame!==undefined)
seek(seq,item.datum.frame)})}}).catch(err=>{console.error(err)})})});
"""


def esc(text: Any) -> str:
    return html.escape(str(text))


class Page:
    """An HTML page built section by section; ``write`` puts the Vega bundle inline."""

    def __init__(self, title: str) -> None:
        self.title = title
        self.parts: list[str] = []
        self.toc: list[tuple[str, str]] = []
        self.n_specs = 0

    def section(self, anchor: str, heading: str) -> None:
        self.toc.append((anchor, heading))
        self.parts.append(f'<h2 id="{esc(anchor)}">{esc(heading)}</h2>')

    def add(self, fragment: str) -> None:
        self.parts.append(fragment)

    def text(self, text: str, cls: str = "note") -> None:
        self.parts.append(f'<p class="{cls}">{esc(text)}</p>')

    def pre(self, text: str) -> None:
        self.parts.append(f"<pre>{esc(text)}</pre>")

    def chart(self, spec: dict[str, Any], sequence: str | None = None) -> None:
        """A Vega-Lite chart; with ``sequence``, a click on a mark seeks that sequence's
        video to the mark's ``frame``."""
        self.n_specs += 1
        sid = f"spec{self.n_specs}"
        data = json.dumps(spec, separators=(",", ":"), allow_nan=False).replace("</", "<\\/")
        seq = f' data-sequence="{esc(sequence)}"' if sequence else ""
        self.parts.append(f'<script type="application/json" id="{sid}">{data}</script>'
                          f'<div class="chart" data-spec="{sid}"{seq}></div>')

    def image(self, path: Path, alt: str, embed: bool = True) -> None:
        """A PNG embedded as a data URI (the page stays whole when copied alone), or with
        ``embed`` False shown from its file, ``alt`` being its path relative to the page."""
        src = (f"data:image/png;base64,{base64.b64encode(path.read_bytes()).decode('ascii')}"
               if embed else alt)
        self.parts.append(f'<figure><img class="plot" alt="{esc(alt)}" src="{esc(src)}">'
                          f'<figcaption class="note">{esc(alt)}</figcaption></figure>')

    def video(self, src: str, sequence: str, first: int, fps: float) -> None:
        """A video of the run folder (``src`` relative to the page), frame ``first`` at 0 s."""
        s = esc(sequence)
        self.parts.append(
            f'<div class="player"><video controls muted preload="auto" src="{esc(src)}" '
            f'data-sequence="{s}" data-first="{int(first)}" data-fps="{float(fps):g}">'
            f'</video><span class="frame" id="frame-{s}">frame {int(first)}</span></div>')

    def write(self, path: Path) -> Path:
        nav = " ".join(f'<a href="#{esc(a)}">{esc(h)}</a>' for a, h in self.toc)
        bundle = vega_bundle().replace("</script", "<\\/script")
        text = ("<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
                f"<title>{esc(self.title)}</title><style>{CSS}</style>"
                f"<script>{bundle}</script><script>{SCRIPT}</script></head><body>"
                f"<h1>{esc(self.title)}</h1><nav>{nav}</nav>\n" + "\n".join(self.parts)
                + "\n</body></html>\n")
        return write_atomic(path, text)


@functools.cache
def vega_bundle() -> str:
    """Vega, Vega-Lite and vega-embed as one script (``window.vegaEmbed``): vl-convert's
    bundle, kept in the occbench cache folder (``occbench.sources.cache.cache_root``) per
    vl-convert version, since making it costs seconds of CPU in every process (each job of a
    sweep); made again when the kept copy is missing or not whole."""
    root = cache_root()
    path = None if root is None else root / f"vega-bundle-{vl_convert.__version__}.js"
    if path is not None and path.is_file():
        text = path.read_text()
        if BUNDLE_MARK in text:
            return text
    text = vl_convert.javascript_bundle()
    if path is not None:
        try:
            write_atomic(path, text)
        except OSError:  # a read-only cache: made again next time
            pass
    return text


def table_html(frame: pd.DataFrame, best: Sequence[bool] | None = None,
               senses: dict[str, int] | None = None, digits: int = 3) -> str:
    """A sortable table (click a header); with ``senses`` (column -> +1 higher is better, -1
    lower, 0 neither), each column's best value is marked."""
    cols = list(frame.columns)
    marks = {c: _best_rows(frame[c], senses.get(c, 0)) for c in cols} if senses else {}
    head = "".join(f'<th onclick="sortTable(this)">{esc(c)}</th>' for c in cols)
    rows = []
    for i, rec in enumerate(frame.itertuples(index=False)):
        cells = []
        for c, v in zip(cols, rec):
            num = pd.api.types.is_number(v) and not isinstance(v, bool)
            cls = [] if num else ["text"]
            if i in marks.get(c, ()):
                cls.append("best")
            shown = _fmt(v, digits)
            data = f' data-v="{v}"' if num and pd.notna(v) else ""
            cells.append(f'<td class="{" ".join(cls)}"{data}>{esc(shown)}</td>')
        rows.append("<tr>" + "".join(cells) + "</tr>")
    return (f'<table class="sortable"><thead><tr>{head}</tr></thead><tbody>'
            + "".join(rows) + "</tbody></table>")


def _fmt(v: Any, digits: int) -> str:
    if isinstance(v, float):
        if math.isnan(v):
            return "-"
        return str(int(v)) if v.is_integer() and abs(v) >= 10 else f"{v:.{digits}f}"
    return str(v)


def _best_rows(values: pd.Series, sense: int) -> set[int]:
    """Rows holding the best value (none when all equal or ``sense`` is 0)."""
    v = pd.to_numeric(values, errors="coerce")
    if sense == 0 or v.isna().all() or v.nunique() < 2:
        return set()
    target = v.max() if sense > 0 else v.min()
    return {i for i, x in enumerate(v.tolist()) if x == target}
