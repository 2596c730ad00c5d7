"""Every step mode reproduces its recorded trajectory to the bit (the record
of tests/trajectory_record.py, taken before the core was split into layers)."""
import json

import pytest

import trajectory_record


def recorded():
    with open(trajectory_record.RECORD) as f:
        return json.load(f)


def test_the_record_covers_every_run():
    assert sorted(recorded()) == sorted(trajectory_record.runs())


@pytest.mark.parametrize("name", sorted(trajectory_record.runs()))
def test_trajectory_matches_the_record(name):
    assert trajectory_record.digest(name) == recorded()[name]
