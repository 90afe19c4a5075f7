"""report.html of a run and of a 2x3 sweep, opened in headless Chromium (Debian's
``chromium``; CI installs it in .ci/run): no console error, no network request, the video
plays to a frame, a click on a timeline event seeks it, tables sort.

One tiny run (the crossing scene, 40 frames, baseline and reta) and one tiny sweep (the
baseline on 30 frames, max_age 1,5 x min_hits 1,2,3, in process) are shared by the tests.
"""

from __future__ import annotations

import json
import re
import shutil
from pathlib import Path

import pytest
from run_scenes import compose_cfg, run_experiment

CHROMIUM = shutil.which("chromium") or "/usr/bin/chromium"
ARGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking",
        "--disable-component-update", "--no-first-run"]
SCENE = ("dataset=synthetic", "dataset.scenarios=[crossing]", "progress=false")


@pytest.fixture(scope="session")
def html_run(tmp_path_factory) -> Path:
    """A finished run with its video: ``occbench report`` wrote report.html again."""
    from occbench.commands.report import main as report_main

    out = tmp_path_factory.mktemp("html_run")
    cfg = compose_cfg(*SCENE, "dataset.length=40", "tracker=all", "~tracker.pbm")
    result = run_experiment(cfg, out, tracker_name="all")
    assert result.ok and result.trackers == ["baseline", "reta"]
    assert (out / "report.html").is_file()  # written by the run itself
    summary = (out / "summary.md").read_text()
    assert "## Paired differences of trackers" in summary and "| baseline | reta |" in summary
    assert [d.metric for d in result.paired] == ["IDF1", "HOTA", "MOTA"]
    assert report_main([str(out), "--no-trajectories"]) == 0
    assert (out / "report" / "crossing.mp4").is_file()
    return out


@pytest.fixture(scope="session")
def html_sweep(tmp_path_factory) -> Path:
    """A finished 2x3 sweep, its jobs run as a multirun runs them (``guarded``)."""
    from occbench.sweeps.gather import guarded, write_sweep
    from occbench.sweeps.jobs import begin_sweep

    root = tmp_path_factory.mktemp("html_sweep")
    swept = ["tracker.max_age=1,5", "tracker.min_hits=1,2,3"]
    begin_sweep(root, ["tracker=baseline", *swept])
    job = 0
    for age in (1, 5):
        for hits in (1, 2, 3):
            over = [f"tracker.max_age={age}", f"tracker.min_hits={hits}"]
            cfg = compose_cfg(*SCENE, "dataset.length=30", "tracker=baseline", *over)
            d = root / str(job)
            guarded(d, over, lambda cfg=cfg, d=d: run_experiment(cfg, d).objective())
            job += 1
    write_sweep(root, plots=False)
    return root


@pytest.fixture(scope="session")
def browser():
    if not Path(CHROMIUM).is_file():
        pytest.skip("no chromium browser here (Debian: apt-get install -y chromium; "
                    ".ci/run installs it)")
    sync_api = pytest.importorskip("playwright.sync_api", reason="pip install -e '.[test]'")
    with sync_api.sync_playwright() as p:
        b = p.chromium.launch(executable_path=CHROMIUM, args=ARGS)
        yield b
        b.close()


def open_page(browser, path: Path):
    """The page loaded with every chart drawn; its console errors and outside requests."""
    page = browser.new_page(viewport={"width": 1200, "height": 900})
    errors: list[str] = []
    outside: list[str] = []
    page.on("console", lambda m: errors.append(m.text) if m.type == "error" else None)
    page.on("pageerror", lambda e: errors.append(str(e)))
    page.on("request", lambda r: outside.append(r.url)
            if not r.url.startswith(("file:", "data:")) else None)
    page.goto(path.resolve().as_uri())
    page.wait_for_function("[...document.querySelectorAll('.chart')]"
                           ".every(e => e.dataset.ready)", timeout=60_000)
    return page, errors, outside


def test_run_page_loads_with_no_error_and_no_network(browser, html_run) -> None:
    page, errors, outside = open_page(browser, html_run / "report.html")
    assert errors == [] and outside == []
    assert page.locator(".chart svg").count() >= 2  # paired differences, the timeline
    text = page.locator("body").inner_text()
    for part in ("COMBINED", "Paired differences", "baseline", "reta", "occbench",
                 "Errors over time", "config.yaml"):
        assert part in text
    # the COMBINED table sorts on a click of its header
    table = page.locator("table.sortable").first
    idf1 = table.locator("th", has_text=re.compile("^IDF1$"))
    idf1.click()
    first = table.locator("tbody tr").first.locator("td").first.inner_text()
    idf1.click()
    assert table.locator("tbody tr").first.locator("td").first.inner_text() != first
    page.close()


def test_video_plays_to_a_frame_and_a_timeline_click_seeks_it(browser, html_run) -> None:
    page, errors, _ = open_page(browser, html_run / "report.html")
    video = "document.querySelector('video[data-sequence=\"crossing\"]')"
    assert page.evaluate(f"{video}.dataset.fps") == "25"
    page.evaluate(f"{video}.play()")
    page.wait_for_function(f"{video}.currentTime >= 0.4", timeout=30_000)  # frame 11
    page.evaluate(f"{video}.pause()")
    shown = int(page.locator("#frame-crossing").inner_text().split()[-1])
    assert shown >= 11 and shown == page.evaluate(f"frameAt({video})")
    # the timeline's events: every (first) frame a mark of the chart starts at
    spec = json.loads(page.evaluate("document.getElementById(document.querySelector("
                                    "'.chart[data-sequence=\"crossing\"]').dataset.spec)"
                                    ".textContent"))
    starts = {row["frame"] for rows in spec["datasets"].values() for row in rows}
    marks = page.locator(".chart[data-sequence='crossing'] g.mark-rect path")
    assert marks.count() >= 1 and starts
    page.evaluate(f"{video}.currentTime = 0")
    marks.first.click()
    page.wait_for_function(f"{video}.currentTime > 0 && !{video}.seeking", timeout=10_000)
    frame = page.evaluate(f"frameAt({video})")
    assert frame in starts
    assert page.evaluate(f"{video}.currentTime") == pytest.approx((frame - 1 + 0.5) / 25)
    assert errors == []
    page.close()


def test_sweep_page_loads_with_no_error_and_no_network(browser, html_sweep) -> None:
    assert (html_sweep / "0" / "report.html").is_file()  # each job has its page
    page, errors, outside = open_page(browser, html_sweep / "report.html")
    assert errors == [] and outside == []
    text = page.locator("body").inner_text()
    for part in ("Best settings", "Best minus second best", "tracker.max_age",
                 "tracker.min_hits", "HOTA against tracker.min_hits", "occbench -m"):
        assert part in text, part
    # each swept parameter against each metric (the sweep's default ones), and the forest
    from occbench.sweeps.tables import DEFAULT_METRICS

    assert page.locator(".chart svg").count() == 2 * len(DEFAULT_METRICS) + 1
    page.close()


def test_report_pages_are_small_and_fetch_nothing(html_run, html_sweep) -> None:
    """No http(s) URL is loaded by the page (scripts and pictures inline; the video and
    the contact sheet are files beside it) and a run's page stays near the Vega bundle's
    size (about 0.9 MB)."""
    for page in (html_run / "report.html", html_sweep / "report.html"):
        text = page.read_text()
        assert not re.search(r"""(src|href)=["']https?:""", text)
        assert page.stat().st_size < 2_000_000
    assert 'src="report/crossing.mp4"' in (html_run / "report.html").read_text()
