"""The tracking graph as a run output: ``graph.export=true`` writes it beside the tracks."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from hydra import compose, initialize_config_dir

from occbench.errors import RunError
from occbench.pipeline.experiment import run_experiment
from occbench.report.graph import GraphExport, read_graph_csv

ROOT = Path(__file__).resolve().parents[3]


def _cfg(*overrides: str):
    with initialize_config_dir(config_dir=str(ROOT / "conf"), version_base="1.3"):
        # a short stop_behind: one person stands still behind a passer-by in mid-sequence
        return compose("config", overrides=["dataset.scenarios=[stop_behind]", "dataset.length=60",
                                            "progress=false", *overrides])


def test_reta_run_writes_graph_beside_tracks_with_all_node_kinds(tmp_path):
    result = run_experiment(_cfg("tracker=all", "graph.export=true"), tmp_path)
    assert result.ok
    tracks = tmp_path / "tracks"
    path = tracks / "reta" / "stop_behind.graph.json"
    assert (tracks / "reta" / "stop_behind.txt").is_file() and path.is_file()
    text = path.read_text()
    assert "NaN" not in text  # strict JSON: rho of unmatched nodes is null
    doc = json.loads(text)
    assert doc["sequence"] == "stop_behind"
    assert any(n["rho"] is None for n in doc["nodes"]) and any(n["rho"] for n in doc["nodes"])
    kinds = {n["kind"] for n in doc["nodes"]}
    assert kinds == {"visible", "hypothesis", "tentative"}
    assert {n["frame"] for n in doc["nodes"]} == set(range(1, 61))
    # every edge joins a node of frame t-1 to one of frame t
    frame_of = {n["node"]: n["frame"] for n in doc["nodes"]}
    assert doc["edges"] and all(frame_of[e["source"]] == e["frame"] - 1 == frame_of[e["target"]] - 1
                                for e in doc["edges"])
    # the hidden person's hypotheses carry its id and the kind of hypothesis
    hyps = [n for n in doc["nodes"] if n["kind"] == "hypothesis"]
    assert {n["hypothesis"] for n in hyps} <= {"velocity", "occluder", "still"}
    assert all(n["id"] > 0 for n in hyps)
    # a tracker keeping no graph writes none
    assert not list((tracks / "baseline").glob("*.graph*"))


def test_graph_export_is_off_by_default_and_csv_on_request(tmp_path):
    run_experiment(_cfg("tracker=reta", "dataset.length=20"), tmp_path / "off", tracker_name="reta")
    assert not list((tmp_path / "off" / "tracks").rglob("*.graph*"))
    run_experiment(_cfg("tracker=reta", "dataset.length=20", "graph.export=true",
                        "graph.format=csv"), tmp_path / "csv", tracker_name="reta")
    stem = tmp_path / "csv" / "tracks" / "reta" / "stop_behind.graph.csv"
    nodes, edges = read_graph_csv(stem)
    assert nodes and edges and {n["frame"] for n in nodes} == {str(k) for k in range(1, 21)}


def test_bad_graph_config_is_a_clear_error(tmp_path):
    with pytest.raises(RunError, match="graph.format"):
        run_experiment(_cfg("tracker=reta", "graph.format=xml"), tmp_path, tracker_name="reta")
    with pytest.raises(ValueError, match="unknown key"):
        GraphExport.from_config({"exprot": True}, tmp_path)
