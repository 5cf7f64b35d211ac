"""The learned slip cue in a Python controller (graspbed.LearnedSlipCue): the same C++ cue the
reference's learned_cue uses, fed the state the controller is given; it rises where the added mass
makes the box slide, and a model file that is not there is refused naming it."""
import os
import sys

import pytest

import graspbed

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "..", "examples"))
from python_controller import ThresholdGrip  # noqa: E402


class CueWatcher(ThresholdGrip):
    """ThresholdGrip that also runs the learned cue every tick and keeps its scores."""

    def __init__(self):
        self.cue = graspbed.LearnedSlipCue()  # before the parent's __init__, which calls reset()
        self.scores = []
        super().__init__()

    def reset(self):
        super().reset()
        self.cue.reset()
        self.scores = []

    def update(self, state, hand, time_s):
        score, flag = self.cue.update(state, time_s)
        self.scores.append((time_s, score, flag))
        return super().update(state, hand, time_s)


def test_the_cue_scores_every_tick_and_rises_when_the_added_mass_slides_the_box():
    controller = CueWatcher()
    graspbed.run("scenarios/added_mass_step.yaml", controller=controller)
    scores = controller.scores
    assert len(scores) > 1000
    assert all(0.0 <= score <= 1.0 for _, score, _ in scores)
    # ThresholdGrip's fixed 3 N does not carry the added 0.4 kg: the box slides from the step at 1.6 s
    # on. Before it, held and lifted (the lift ends at 1.3 s), the cue stays low (the close's own
    # transient is not a held grasp: the reference arms the cue only while holding).
    before = max(score for t, score, _ in scores if 1.0 <= t < 1.6)
    after = max(score for t, score, _ in scores if t >= 1.6)
    assert after >= controller.cue.threshold > before


def test_a_missing_model_file_is_refused_naming_it():
    with pytest.raises(ValueError, match="no_such_model.json"):
        graspbed.LearnedSlipCue("no_such_model.json")
