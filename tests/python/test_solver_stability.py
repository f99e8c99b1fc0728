"""scripts/analysis/particle_solver_stability.py: the linear model of the particle solver's step
that docs/particles.md ("Known limits") quotes."""

import importlib.util
import os
from pathlib import Path

import pytest

SOURCE = Path(os.environ.get("TENDRIL_SOURCE_DIR", Path(__file__).resolve().parents[2]))
spec = importlib.util.spec_from_file_location(
    "particle_solver_stability", SOURCE / "scripts" / "analysis" / "particle_solver_stability.py")
model = importlib.util.module_from_spec(spec)
spec.loader.exec_module(model)


def test_following_the_parents_one_way_amplifies_what_the_eigenvalues_call_stable():
    one_way = model.step_matrix(24, stiffness=1.0)
    assert model.spectral_radius(one_way) < 0.7
    # A disturbance grows some two hundredfold before it dies out...
    assert model.transient_growth(one_way, steps=200) > 100.0
    # ...against at most the chain's own lever with the groups' fits alone (no parent frames).
    symmetric = model.step_matrix(24, stiffness=1.0, own=1.0)
    assert model.transient_growth(symmetric, steps=200) < 24.0


def test_softer_matching_amplifies_more_and_long_soft_chains_diverge():
    stiff = model.transient_growth(model.step_matrix(24, stiffness=1.0), steps=200)
    soft = model.transient_growth(model.step_matrix(24, stiffness=0.4), steps=200)
    assert soft > 100.0 * stiff
    assert model.spectral_radius(model.step_matrix(80, stiffness=0.4)) > 1.0


def test_without_velocity_kept_the_passes_amplify_only_by_the_lever():
    assert model.transient_growth(model.step_matrix(24, stiffness=0.4, carry=False), steps=200) < 30.0


def test_bad_arguments_are_refused():
    for kwargs in ({"n": 1}, {"n": 10, "stiffness": 0.0}, {"n": 10, "own": 1.5}, {"n": 10, "passes": 0},
                   {"n": 10, "damping": 1.0}):
        with pytest.raises(ValueError):
            model.step_matrix(**kwargs)
    assert model.main(["--particles", "1"]) == 2
