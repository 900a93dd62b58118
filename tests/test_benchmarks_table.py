"""benchmarks/table.py: formatting, the README block, and every benchmark script's rows().

No benchmark runs here: the rows are made up, and the scripts are only imported.
"""

import importlib.util
import inspect
import sys
from pathlib import Path

import pytest

BENCHMARKS = Path(__file__).resolve().parents[1] / "benchmarks"
pytestmark = pytest.mark.skipif(not BENCHMARKS.is_dir(), reason="needs the source tree")


def _load(name: str, monkeypatch):
    spec = importlib.util.spec_from_file_location(name, BENCHMARKS / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    monkeypatch.setitem(sys.modules, name, module)  # dataclasses look their module up
    spec.loader.exec_module(module)
    return module


@pytest.fixture
def table(monkeypatch):
    monkeypatch.syspath_prepend(str(BENCHMARKS))  # the scripts import _common beside them
    return _load("table", monkeypatch)


ROWS = [
    {
        "benchmark": "FISTA vs cvxpy",
        "case": "stacked, lambda 0.1",
        "ssecert": 0.00123456,
        "reference": 0.0125,
        "reference_name": "cvxpy + Clarabel",
        "ratio": 0.0125 / 0.00123456,
        "note": "median of 5 instances",
    },
    {
        "benchmark": "enumeration vs rank loop",
        "case": "random n = 15 | p = 30",
        "ssecert": 0.55,
        "reference": 38.2,
        "reference_name": "numpy matrix_rank per set",
        "ratio": 38.2 / 0.55,
        "note": "decisions agree on the sample: yes",
    },
    {
        "benchmark": "cost model projection",
        "case": "C(60, 10), 64 workers",
        "ssecert": 1404.0,
        "reference": None,
        "reference_name": "-",
        "ratio": None,
        "note": "not run",
    },
]


def test_numbers_have_a_few_significant_digits(table):
    assert table.format_seconds(0.00123456) == "1.23 ms"
    assert table.format_seconds(4.5e-6) == "4.50 us"
    assert table.format_seconds(38.2) == "38.2 s"
    assert table.format_seconds(1404.0) == "23.4 min"
    assert table.format_seconds(25 * 3600.0) == "25.0 h"
    assert table.format_seconds(None) == "-"
    assert table.format_ratio(69.7) == "70x"
    assert table.format_ratio(3.744) == "3.74x"
    assert table.format_ratio(2.034) == "2.03x"
    assert table.format_ratio(0.02345) == "0.0234x"
    assert table.format_ratio(None) == "-"
    assert table.format_ratio(float("nan")) == "n/a"


def test_tables_group_rows_and_show_a_missing_reference(table):
    full = table.full_table(ROWS).splitlines()
    assert full[0].startswith("| benchmark | case | ssecert | reference | ratio |")
    body = full[2:]
    assert len(body) == 3
    # grouped in the table's order, whatever order the scripts gave them in
    assert body[0].startswith("| enumeration vs rank loop |")
    assert body[1].startswith("| FISTA vs cvxpy |")
    assert "| 69x |" in body[0]
    assert "random n = 15 \\| p = 30" in body[0]  # a | in a cell is escaped
    assert "| 23.4 min | - | - | - | not run |" in body[2]
    compact = table.compact_table(ROWS).splitlines()
    assert compact[0] == "| benchmark | case | ssecert | reference | ratio |"
    assert compact[2].endswith("| 550 ms | 38.2 s | 69x |")
    assert all(line.count("|") == 6 for line in compact[:2])


def test_readme_block_is_replaced_in_place(table):
    text = f"# x\n\n## Performance\n\nprose\n\n{table.START}\nold\n{table.END}\n\n## References\n"
    new = table.replace_block(text, "new table\n")
    assert new == text.replace("\nold\n", "\nnew table\n")
    assert table.replace_block(new, "new table\n") == new


def test_readme_block_is_added_under_performance(table):
    text = "# x\n\n## Performance\n\nprose\n\n## References\n\nrefs\n"
    new = table.replace_block(text, "rows\n")
    block = f"{table.START}\nrows\n{table.END}"
    assert new == f"# x\n\n## Performance\n\nprose\n\n{block}\n\n## References\n\nrefs\n"
    bare = table.replace_block("# x\n\n## References\n\nrefs\n", "rows\n")
    assert bare == f"# x\n\n## Performance\n\n{block}\n\n## References\n\nrefs\n"
    assert table.replace_block("# x\n", "rows\n") == f"# x\n\n## Performance\n\n{block}\n"
    with pytest.raises(ValueError, match="only one of"):
        table.replace_block(f"# x\n{table.START}\n", "rows\n")


def test_generated_readme_names_the_machine_and_the_mode(table):
    results = {
        "machine": {
            "cpus": 2,
            "cpu_model": "Example CPU",
            "python": "3.11.7",
            "numpy": "2.0",
            "scipy": "1.14",
        },
        "benchmarks": {
            "fista": {"rows": ROWS[:1], "seconds": 75.0, "date": "2026-01-02T03:04:05+00:00"}
            | {"quick": True},
            "distributed": {"rows": ROWS[1:], "seconds": 30.0, "date": "2026-01-02T04:00:00"}
            | {"quick": True},
        },
    }
    readme = table.benchmarks_readme(results)
    assert "2 CPUs: Example CPU" in readme
    assert "numpy 2.0, scipy 1.14" in readme
    assert "quick run (--quick), 2026-01-02" in readme
    assert "took 105 s in all" in readme
    assert "**analyze** (`bench_analyze.py`; not run yet)" in readme
    assert readme.count("| FISTA vs cvxpy |") == 1
    block = table.compact_block(results)
    assert "2 CPUs" in block and "| 69x |" in block


def test_every_benchmark_script_exposes_rows(table, monkeypatch):
    # bench_fista asks for one BLAS thread when imported: keep that out of this process
    for variable in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
        monkeypatch.setenv(variable, "0")
    scripts = sorted(p.stem for p in BENCHMARKS.glob("bench_*.py"))
    assert {f"{script}.py" for script in scripts} == {s for s, _ in table.BENCHMARKS.values()}
    for script in scripts:
        module = _load(script, monkeypatch)
        signature = inspect.signature(module.rows)
        assert list(signature.parameters) == ["quick"], script
        assert signature.parameters["quick"].default is False, script


def test_a_run_with_nothing_to_measure_keeps_the_rows_measured_before(table):
    here = {"cpus": 2, "cpu_model": "AMD EPYC"}
    gpu = {"rows": ROWS[:1], "machine": {"cpus": 16, "cpu_model": "Xeon"}, "seconds": 25.0}
    empty = {"rows": [], "machine": here, "seconds": 0.8}
    assert table.kept_entry(gpu, empty) is gpu  # no GPU here
    flint = {"rows": ROWS[1:2], "machine": here, "seconds": 2.0}
    assert table.kept_entry(flint, empty) is flint  # python-flint not installed now
    # rows measured now replace them; an empty run replaces an empty entry or none
    measured = {"rows": ROWS[1:2], "machine": here, "seconds": 30.0}
    assert table.kept_entry(gpu, measured) is measured
    assert table.kept_entry(None, empty) is empty
    assert table.kept_entry({"rows": [], "machine": here}, empty) is empty
