"""The certificate's matrices as a MATLAB .mat file (``ssecert analyze SPEC --mat PATH``)."""

import json
import math

import numpy as np
import scipy.io

from ssecert.cli import main
from ssecert.report.mat import certificate_arrays


def test_analyze_writes_the_matrices_the_json_holds(tmp_path, capsys):
    mat, js = tmp_path / "c.mat", tmp_path / "c.json"
    assert main(["analyze", "notes-example-2", "--mat", str(mat), "--json", str(js)]) == 1
    assert "matrices written to" in capsys.readouterr().out
    data = scipy.io.loadmat(mat)
    document = json.loads(js.read_text())
    witness = document["checks"]["sparse_observability"]["witness"]
    assert np.array_equal(data["sparse_observability__witness__z"].ravel(), witness["z"])
    assert np.array_equal(
        data["sparse_observability__breaking_set"].ravel(),
        document["checks"]["sparse_observability"]["breaking_set"],
    )
    assert data["A"].shape == (3, 3) and data["C"].shape == (5, 3)
    assert [str(s[0]) for s in data["sensors"].ravel()] == document["system"]["sensors"]


def test_non_finite_entries_and_ragged_lists():
    document = {
        "system": {"sensors": ["a"]},
        "checks": {
            "x": {"value": [1.0, "Infinity", "NaN"], "ragged": [[1.0], [1.0, 2.0]],
                  "words": ["a", "b"], "flag": [True, False]},
        },
    }  # fmt: skip
    arrays = certificate_arrays(document)
    assert arrays["x__value"][0] == 1.0 and math.isinf(arrays["x__value"][1])
    assert math.isnan(arrays["x__value"][2])
    assert "x__ragged" not in arrays and "x__words" not in arrays and "x__flag" not in arrays
    assert "x__ragged__1" in arrays  # its rows, each a vector


def test_a_binary_file_is_not_written_to_stdout_and_nothing_is_half_written(tmp_path, capsys):
    assert main(["analyze", "notes-example-2", "--mat", "-"]) == 2
    assert "--mat -: a .mat file is binary" in capsys.readouterr().err
    js = tmp_path / "c.json"
    missing = tmp_path / "no-such-folder" / "c.mat"
    assert main(["analyze", "notes-example-2", "--json", str(js), "--mat", str(missing)]) == 2
    assert "--mat" in capsys.readouterr().err and not js.exists()
