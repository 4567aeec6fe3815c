"""The optimizer from Python: settings as keywords, records through a callback that can stop the run."""
import json

import numpy as np
import pytest

import quijibo


def test_callback_stops_the_run_where_asked(tiny_case, tmp_path):
    records = []

    def stop_at_third_iteration(record):
        records.append(record)
        return record["type"] == "iteration" and record["iteration"] == 3

    initial = tiny_case["rational_map"]
    out = tmp_path / "run"
    m, summary = quijibo.optimize(tiny_case["grid"], initial, "12(F)", stop_at_third_iteration, out=str(out),
                                  max_iterations={"F": 50})
    iterations = [r for r in records if r["type"] == "iteration"]
    assert [r["iteration"] for r in iterations] == [1, 2, 3]
    assert summary["complete"] is False and summary["stop_reason"] == "aborted by a callback"
    # The records are the log's lines, field for field.
    log = [json.loads(line) for line in (out / "log.jsonl").read_text().splitlines()]
    assert log == records
    # The result is the best map so far; the initial map is unchanged.
    assert m.variable_count == initial.variable_count
    assert np.array_equal(initial.variables, tiny_case["rational_map"].variables)
    assert summary["absolute_end"] <= summary["absolute_start"]
    # resume=True continues from the checkpoint the abort wrote, to the end.
    m2, s2 = quijibo.optimize(tiny_case["grid"], initial, "12(F)", out=str(out), resume=True, max_iterations={"F": 50})
    assert s2["complete"] is True and s2["passes"][0]["iterations"] > 3


def test_optimize_without_out_leaves_no_folder_and_returns_the_map(tiny_case, tmp_path, monkeypatch):
    import tempfile

    monkeypatch.setenv("TMPDIR", str(tmp_path))
    tempfile.tempdir = None
    try:
        m, summary = quijibo.optimize(tiny_case["grid"], tiny_case["rational_map"], "12(VF)",
                                      max_iterations={"V": 5, "F": 10}, alpha=8, weights="balanced",
                                      between_nodes="off")  # psi on the nodes, as energy() gives it
    finally:
        tempfile.tempdir = None
    assert summary["complete"] is True and "stop_reason" not in summary
    assert summary["absolute_end"] < summary["absolute_start"]
    assert list(tmp_path.iterdir()) == []
    # The returned map's energy on the finest grid is the summary's (balanced weights, alpha 8).
    e = quijibo.energy(m, tiny_case["grid"], weights="balanced", alpha=8, gradient=False)
    assert e.energy == pytest.approx(summary["absolute_end"], rel=1e-12, abs=1e-15)


def test_callback_exception_and_bad_settings(tiny_case):
    class Boom(Exception):
        pass

    def boom(record):
        if record["type"] == "iteration":
            raise Boom("from the callback")

    with pytest.raises(Boom, match="from the callback"):
        quijibo.optimize(tiny_case["grid"], tiny_case["rational_map"], "12(F)", boom)
    with pytest.raises(quijibo.Error, match=r'optimize: /alpah: unknown key \(did you mean "alpha"\?\)'):
        quijibo.optimize(tiny_case["grid"], tiny_case["rational_map"], "12(F)", alpah=3)
    with pytest.raises(quijibo.Error, match="optimize: /evaluator"):
        quijibo.optimize(tiny_case["grid"], tiny_case["rational_map"], evaluator="fastest")
    with pytest.raises(quijibo.Error, match="resume"):
        quijibo.optimize(tiny_case["grid"], tiny_case["rational_map"], resume=True)


def test_ctrl_c_writes_a_checkpoint_and_raises_keyboard_interrupt(tiny_case, tmp_path):
    import os
    import signal

    def interrupt_at_fifth(record):
        if record["type"] == "iteration" and record["iteration"] == 5:
            os.kill(os.getpid(), signal.SIGINT)  # as Ctrl-C would, during the run

    out = tmp_path / "run"
    with pytest.raises(KeyboardInterrupt, match="checkpoint written"):
        quijibo.optimize(tiny_case["grid"], tiny_case["rational_map"], "12(F)", interrupt_at_fifth, out=str(out),
                         max_iterations={"F": 50})
    checkpoint = json.loads((out / "checkpoint.json").read_text())
    assert checkpoint["iteration"] == 5
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler  # Python's handler is back
    m, summary = quijibo.optimize(tiny_case["grid"], tiny_case["rational_map"], "12(F)", out=str(out), resume=True,
                                  max_iterations={"F": 50})
    assert summary["complete"] is True


def test_without_out_the_map_is_the_one_written_with_out(tiny_case, tmp_path):
    # Both go through the pipeline's optimize stage, as `quijibo optimize`; the folder changes
    # nothing but the files.
    settings = dict(max_iterations={"V": 5, "F": 10}, alpha=8)
    out = tmp_path / "run"
    a, sa = quijibo.optimize(tiny_case["grid"], tiny_case["rational_map"], "12(VF)", out=str(out), **settings)
    b, sb = quijibo.optimize(tiny_case["grid"], tiny_case["rational_map"], "12(VF)", **settings)
    assert np.array_equal(a.variables, b.variables)
    assert sa["absolute_end"] == sb["absolute_end"] and sa["best_pass"] == sb["best_pass"]
    assert np.array_equal(quijibo.read_map(str(out / "map.json")).variables, a.variables)
    assert (out / "initial_map.json").exists() and (out / "log.jsonl").exists()
