"""The speed gate's own logic (bench/speed_gate.py, issue 49), without valgrind: a count grown by
more than the tolerance fails, a baseline updated in the same diff passes only with a
CHANGELOG.md line naming it, and a machine without a baseline of its kind fails."""

import importlib.util
import json
import shutil
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
spec = importlib.util.spec_from_file_location("speed_gate", ROOT / "bench" / "speed_gate.py")
speed_gate = importlib.util.module_from_spec(spec)
spec.loader.exec_module(speed_gate)

COUNTS = {"trace s3_3072 32³": 24_000_000, "build ico6": 650_000_000}
ENV = {"ndtrace": "0.1.0", "python": "3.11.2", "valgrind": "valgrind-3.19.0",
       "machine": "x86_64", "avx2": True}


def test_a_count_above_the_tolerance_fails_and_one_within_passes():
    grown = dict(COUNTS, **{"build ico6": int(650_000_000 * 1.031)})
    failed, lines = speed_gate.compare(grown, COUNTS, 0.03)
    assert failed == ["build ico6: +3.1% instructions"]
    assert any(l.startswith("build ico6") and l.endswith("FAIL") for l in lines)
    within = dict(COUNTS, **{"build ico6": int(650_000_000 * 1.029)})
    assert speed_gate.compare(within, COUNTS, 0.03)[0] == []
    # A gain passes and asks for the baseline to be lowered.
    lower = dict(COUNTS, **{"trace s3_3072 32³": 20_000_000})
    failed, lines = speed_gate.compare(lower, COUNTS, 0.03)
    assert failed == [] and any("lower it with --update" in l for l in lines)


def test_a_count_missing_on_either_side_fails():
    failed, _ = speed_gate.compare({"build ico6": 650_000_000}, COUNTS)
    assert failed == ["trace s3_3072 32³: in the baseline but not measured"]
    failed, _ = speed_gate.compare(dict(COUNTS, extra=1), COUNTS)
    assert failed == ["extra: not in the baseline (record it with --update)"]


def git(repo: Path, *args: str) -> None:
    subprocess.run(["git", "-C", str(repo), "-c", "user.name=t", "-c", "user.email=t@t", *args],
                   check=True, capture_output=True)


@pytest.mark.skipif(shutil.which("git") is None, reason="needs git")
def test_an_updated_baseline_passes_only_with_a_changelog_line(tmp_path, monkeypatch):
    monkeypatch.delenv("SPEED_GATE_BASE", raising=False)
    repo = tmp_path / "repo"
    (repo / "bench").mkdir(parents=True)
    path = repo / "bench" / "speed_gate.json"
    changelog = repo / "CHANGELOG.md"
    changelog.write_text("# Changelog\n\n## [Unreleased]\n")
    speed_gate.update(COUNTS, ENV, str(path))
    git(repo, "init", "-q", "-b", "main")
    git(repo, "add", ".")
    git(repo, "commit", "-q", "-m", "baseline")
    git(repo, "checkout", "-q", "-b", "change")

    def run(counts):
        return speed_gate.gate(counts, ENV, str(repo), str(path))

    assert run(COUNTS)[0]
    # A change that costs 10 % more instructions fails against the checked-in baseline.
    grown = {k: int(v * 1.10) for k, v in COUNTS.items()}
    passed, report = run(grown)
    assert not passed and "+10.0% instructions" in report[-1]
    # The baseline updated in the same diff, but without saying why: still fails.
    speed_gate.update(grown, ENV, str(path))
    passed, report = run(grown)
    assert not passed and "without a CHANGELOG.md line" in report[-1]
    # ... and with a CHANGELOG.md line naming it: passes, committed or not.
    changelog.write_text(changelog.read_text() + "- bench/speed_gate.json: exact leaf tests, "
                         "+10 % instructions for 40 % less memory.\n")
    assert run(grown) == (True, run(grown)[1])
    assert run(grown)[1][-1] == "speed-gate: passed"
    git(repo, "commit", "-q", "-am", "change")
    assert run(grown)[0]
    # A baseline not yet added to git is a change too.
    git(repo, "checkout", "-q", "-b", "new", "main")
    git(repo, "rm", "-q", "--cached", "bench/speed_gate.json")
    git(repo, "commit", "-q", "-m", "no baseline")
    assert not run(COUNTS)[0]
    git(repo, "checkout", "-q", "-f", "change")
    # A line that does not name the baseline does not count.
    git(repo, "checkout", "-q", "-b", "other", "main")
    speed_gate.update(grown, ENV, str(path))
    changelog.write_text(changelog.read_text() + "- Faster traces.\n")
    assert not run(grown)[0]


def test_a_machine_without_a_baseline_of_its_kind_fails(tmp_path):
    path = tmp_path / "speed_gate.json"
    speed_gate.update(COUNTS, ENV, str(path))
    portable = dict(ENV, avx2=False)
    passed, report = speed_gate.gate(COUNTS, portable, str(tmp_path), str(path))
    assert not passed and "no baseline for x86_64-portable" in report[-1]
    # Recording it keeps the other kind's.
    speed_gate.update(COUNTS, portable, str(path))
    assert sorted(json.loads(path.read_text())["baselines"]) == ["x86_64-avx2", "x86_64-portable"]
    assert speed_gate.gate(COUNTS, portable, str(tmp_path), str(path))[0]
