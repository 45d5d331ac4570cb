"""One static HTML page per batch or search: its runs in a sortable table, worst first, and a page per run.

``report.html`` in the batch's (or search's) folder shows the overview figures (a search's
progress and boundary figures, a batch's overview), then a table of every run: its rank,
status, verdicts, figures and parameters, the worst first (a search: the lowest objective;
a batch: the runs that did not pass).  A click on a column's header sorts by it (again:
the other way); ``report.html#sort=<column>`` (``-<column>``: descending) opens it sorted.
Each run's id links to ``report/<run-id>.html``: its verdicts, parameters, figures (the
track first, from the run's own folder) and its key time series (``[report] series`` of the
batch file, else the first few of the run's columns) drawn inline as SVG.  No server, no
network: the CSS and the script are in the page, the figures are relative links.
"""

from __future__ import annotations

import html
import json
import math
from pathlib import Path

from orchestrator.errors import ScenarioError

#: Time series drawn per run when the batch file names none.
DEFAULT_SERIES = 4
#: Points per drawn time series at most (the rest are skipped evenly).
SERIES_POINTS = 400

_STYLE = """
body{font-family:sans-serif;margin:1.5em;color:#222}
table{border-collapse:collapse;font-size:13px}
th,td{border:1px solid #ccc;padding:3px 6px;text-align:left;white-space:nowrap}
th{background:#eee;cursor:pointer;position:sticky;top:0}
tr.bad td{background:#fde8e8}
img{max-width:100%;border:1px solid #ddd;margin:4px 0}
.figs img{max-width:48%}
svg{background:#fafafa;border:1px solid #ddd;margin:4px}
"""

_SCRIPT = """
function cellValue(row, i){const c=row.cells[i];const v=c.getAttribute('data-v');
 if(v===null||v==='')return null;const n=Number(v);return isNaN(n)?v:n;}
function sortBy(column, descending){
 const table=document.getElementById('runs');const head=table.tHead.rows[0];
 let i=-1;for(let k=0;k<head.cells.length;k++){if(head.cells[k].getAttribute('data-col')===column)i=k;}
 if(i<0)return;const body=table.tBodies[0];const rows=Array.from(body.rows);
 rows.sort(function(a,b){const x=cellValue(a,i),y=cellValue(b,i);
  if(x===null&&y===null)return 0;if(x===null)return 1;if(y===null)return -1;
  const r=(typeof x==='number'&&typeof y==='number')?x-y:String(x).localeCompare(String(y));
  return descending?-r:r;});
 rows.forEach(function(r){body.appendChild(r);});
 table.setAttribute('data-sorted',(descending?'-':'')+column);}
document.addEventListener('DOMContentLoaded',function(){
 const head=document.getElementById('runs').tHead.rows[0];
 Array.from(head.cells).forEach(function(th){th.addEventListener('click',function(){
  const table=document.getElementById('runs');const col=th.getAttribute('data-col');
  sortBy(col, table.getAttribute('data-sorted')===col);});});
 const m=/sort=(-?)([^&]+)/.exec(decodeURIComponent(location.hash));
 if(m)sortBy(m[2], m[1]==='-');});
"""


def write_report(folder) -> Path:
    """Write ``folder/report.html`` and ``folder/report/<run-id>.html`` for a batch or search folder.

    Raises
    ------
    ScenarioError
        When ``folder`` holds neither a search (``search.json``) nor a batch (``batch.json``)
        with its table (``summary.parquet``).
    """
    import pandas as pd

    folder = Path(folder)
    kind = "search" if (folder / "search.json").is_file() else "batch" if (folder / "batch.json").is_file() else None
    if kind is None:
        raise ScenarioError(f"{folder}: not a batch or search results folder (no batch.json or search.json)")
    try:
        manifest = json.loads((folder / f"{kind}.json").read_text())
        table = pd.read_parquet(folder / "summary.parquet")
    except (OSError, ValueError) as exc:
        raise ScenarioError(f"{folder}: cannot read its {kind}.json and summary.parquet: {exc}") from None
    table = ranked(table, kind)
    pages = folder / "report"
    pages.mkdir(exist_ok=True)
    series = manifest.get("report_series") or []
    for _, row in table.iterrows():
        (pages / f"{row['run_id']}.html").write_text(_run_page(folder, row, series))
    (folder / "report.html").write_text(_index_page(folder, kind, manifest, table))
    return folder / "report.html"


def ranked(table, kind: str):
    """The runs worst first, with a ``rank`` column (1: the worst).

    A search: runs without an objective (failed, not run) first, then the lowest objective.
    A batch: runs that did not pass first, in their order.
    """
    table = table.copy()
    if kind == "search" and "objective" in table.columns:
        table["_key"] = table["objective"].fillna(-math.inf)
        table = table.sort_values(["_key", "evaluation"], kind="stable").drop(columns="_key")
    else:
        table = table.sort_values(["passed"], kind="stable")
    table.insert(0, "rank", range(1, len(table) + 1))
    return table.reset_index(drop=True)


def _index_page(folder: Path, kind: str, manifest: dict, table) -> str:
    title = f"{kind} {manifest.get('name', folder.name)}"
    parts = [f"<h1>{_e(title)}</h1>"]
    if manifest.get("description"):
        parts.append(f"<p>{_e(manifest['description'])}</p>")
    if kind == "search":
        first = manifest.get("first_failure")
        best = manifest.get("best")
        parts.append(
            f"<p id='findings'>{_e(manifest.get('sampler', ''))} search, seed {_e(manifest.get('seed'))}: "
            f"{len(table)} evaluations of {_e(manifest.get('evaluations'))}; objective <code>{_e(manifest.get('objective'))}"
            f"</code> (minimised){_fails_text(manifest)}; lowest {_number(best)}; "
            f"{manifest.get('failures', 0)} failures"
            + (f", the first at evaluation {first}" if first else ", none found") + ".</p>")
        figures = ["progress.png", "boundary.png"]
    else:
        passed = int(table["passed"].sum()) if "passed" in table.columns else 0
        parts.append(f"<p id='findings'>{passed}/{len(table)} runs passed.</p>")
        figures = ["overview.png"]
    parts += [f"<img src='{name}' alt='{name}'>" for name in figures if (folder / name).is_file()]
    if kind == "search" and (folder / "worst").is_dir():
        files = sorted(p.name for p in (folder / "worst").glob("*.toml"))
        if files:
            parts.append("<p>Worst cases as one-run batch files: "
                         + ", ".join(f"<a href='worst/{_e(f)}'>{_e(f)}</a>" for f in files) + "</p>")
    parts.append(_table(folder, table))
    return _page(title, "\n".join(parts), script=True)


def _fails_text(manifest: dict) -> str:
    below = manifest.get("fails_below")
    return f", a failure below {below:g}" if isinstance(below, (int, float)) else ""


def _table(folder: Path, table) -> str:
    hidden = {"run_id", "reason", "wall_time_s"}
    first = [c for c in ("evaluation", "objective", "failure", "status", "passed", "failed_criteria") if c in table.columns]
    columns = first + [c for c in table.columns if c not in hidden and c not in first]
    head = ["<th data-col='rank'>rank</th>", "<th data-col='run'>run</th>", "<th data-col='track'>track</th>"]
    head += [f"<th data-col='{_e(c)}'>{_e(c)}</th>" for c in columns if c != "rank"]
    rows = []
    for _, row in table.iterrows():
        identifier = row["run_id"]
        bad = bool(row.get("failure", False)) or not bool(row.get("passed", True))
        track = f"runs/{identifier}/track.png"
        cells = [_cell(row["rank"]),
                 f"<td data-v='{_e(identifier)}'><a class='run' href='report/{_e(identifier)}.html'>{_e(identifier)}</a></td>",
                 f"<td data-v='{_e(identifier)}'><a class='track' href='{_e(track)}'>track</a></td>"
                 if (folder / track).is_file() else "<td data-v=''></td>"]
        cells += [_cell(row[c]) for c in columns if c != "rank"]
        rows.append(f"<tr class='{'bad' if bad else 'ok'}' data-run='{_e(identifier)}'>" + "".join(cells) + "</tr>")
    return ("<table id='runs' data-sorted='rank'><thead><tr>" + "".join(head) + "</tr></thead><tbody>\n"
            + "\n".join(rows) + "\n</tbody></table>")


def _cell(value) -> str:
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return "<td data-v=''></td>"
    if isinstance(value, bool) or type(value).__name__ == "bool_":
        return f"<td data-v='{int(bool(value))}'>{'yes' if value else 'no'}</td>"
    if isinstance(value, (int, float)) or type(value).__module__ == "numpy":
        return f"<td data-v='{float(value)!r}'>{_number(value)}</td>"
    return f"<td data-v='{_e(value)}'>{_e(value)}</td>"


def _run_page(folder: Path, row, series: list[str]) -> str:
    identifier = row["run_id"]
    run = folder / "runs" / identifier
    summary = _read_json(run / "summary.json")
    parts = ["<p><a href='../report.html'>all runs</a></p>", f"<h1>run {_e(identifier)} (rank {row['rank']})</h1>",
             f"<p>status: <b>{_e(summary.get('status', row.get('status')))}</b> {_e(summary.get('reason', ''))}</p>"]
    facts = [(k, v) for k, v in row.items() if k not in ("run_id",) and not k.startswith("param:")]
    params = [(k[len("param:"):], v) for k, v in row.items() if k.startswith("param:")]
    parts.append("<h2>verdicts and figures</h2><table>" + "".join(
        f"<tr><th>{_e(k)}</th>{_cell(v)}</tr>" for k, v in facts) + "</table>")
    if params:
        parts.append("<h2>parameters</h2><table>" + "".join(
            f"<tr><th>{_e(k)}</th>{_cell(v)}</tr>" for k, v in params) + "</table>")
    figures = sorted((p.name for p in run.glob("*.png")), key=lambda n: (n != "track.png", n))
    if figures:
        parts.append("<h2>figures</h2><div class='figs'>" + "".join(
            f"<img class='figure' src='../runs/{_e(identifier)}/{_e(name)}' alt='{_e(name)}'>" for name in figures)
            + "</div>")
    parts.append(_series_svg(run / "timeseries.parquet", series))
    return _page(f"run {identifier}", "\n".join(parts))


def _series_svg(path: Path, series: list[str]) -> str:
    """The key time series of a run as small inline SVG plots (none when the run wrote no time series)."""
    import pandas as pd
    import pyarrow.parquet as pq

    if not path.is_file():
        return "<p>no time series (the run did not finish)</p>"
    try:
        available = pq.read_schema(path).names
    except (OSError, ValueError):
        return "<p>time series unreadable</p>"
    names = [s for s in series if s in available] if series else [
        c for c in available if c != "time_s" and "[" not in c][:DEFAULT_SERIES]
    if not names or "time_s" not in available:
        return ""
    frame = pd.read_parquet(path, columns=["time_s", *names])
    step = max(1, len(frame) // SERIES_POINTS)
    frame = frame.iloc[::step]
    plots = ["<h2>time series</h2>"]
    width, height, pad = 420, 140, 30
    t = frame["time_s"].to_numpy(dtype=float)
    for name in names:
        y = pd.to_numeric(frame[name], errors="coerce").to_numpy(dtype=float)
        good = ~(pd.isna(y))
        if not good.any():
            continue
        t0, t1 = float(t[good].min()), float(t[good].max())
        y0, y1 = float(y[good].min()), float(y[good].max())
        spread_t, spread_y = (t1 - t0) or 1.0, (y1 - y0) or 1.0
        points = " ".join(f"{pad + (ti - t0) / spread_t * (width - pad - 5):.1f},"
                          f"{height - pad + 5 - (yi - y0) / spread_y * (height - pad - 10):.1f}"
                          for ti, yi in zip(t[good], y[good]))
        plots.append(
            f"<svg class='series' data-series='{_e(name)}' width='{width}' height='{height}' "
            f"xmlns='http://www.w3.org/2000/svg'><text x='{pad}' y='12' font-size='11'>{_e(name)}</text>"
            f"<text x='2' y='{height - pad + 5}' font-size='9'>{_number(y0)}</text>"
            f"<text x='2' y='22' font-size='9'>{_number(y1)}</text>"
            f"<text x='{width - 90}' y='{height - 4}' font-size='9'>time {t0:.0f}-{t1:.0f} s</text>"
            f"<polyline fill='none' stroke='steelblue' stroke-width='1.2' points='{points}'/></svg>")
    return "\n".join(plots)


def _page(title: str, body: str, script: bool = False) -> str:
    code = f"<script>{_SCRIPT}</script>" if script else ""
    return (f"<!DOCTYPE html>\n<html lang='en'><head><meta charset='utf-8'><title>{_e(title)}</title>"
            f"<style>{_STYLE}</style>{code}</head><body>\n{body}\n</body></html>\n")


def _read_json(path: Path) -> dict:
    try:
        return json.loads(path.read_text())
    except (OSError, ValueError):
        return {}


def _number(value) -> str:
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return ""
    if isinstance(value, bool):
        return "yes" if value else "no"
    value = float(value)
    return f"{value:.0f}" if value.is_integer() and abs(value) < 1e15 else f"{value:.4g}"


def _e(value) -> str:
    return html.escape(str(value), quote=True)
