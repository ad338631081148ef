"""Tests of the scorecard's scoring rules on hand-made reports (no oracle,
no bikedyn): `python3 -m unittest discover -s scorecard` (CI runs it).

The rules are issue 33's: a cause is found when it is selected, or named as
not separable from a selected candidate that is plausible under its prior;
rolling resistance and drag are never false causes."""
from __future__ import annotations

import os
import sys
import unittest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import oracle_scorecard as sc  # noqa: E402

ROW = {"name": "front_steer_inertia_high", "effects": "dIE33_rel=0.5"}
TRUTH = {"nominal_thesis_parameters": {"I4z": 0.0385, "I5x": 0.0525}}


def error(eigen, roll):
    """An error block of a report: the weave RMS (1/s) and roll RMS (rad)."""
    runs = [{"held_out_roll_rms": roll}]
    return {"eigen_rms": eigen, "median_run_roll_rms": roll, "per_run": runs,
            "held_out": {"eigen_rms": eigen}}


def report(selected, parameters, confounded=()):
    return {
        "selected_effects": ["rolling_resistance (speed decay)", "aero_drag (speed decay)"] + selected,
        "parameters": parameters,
        "confounded": [{"chosen": ch, "rival": rv, "confounded": True} for ch, rv in confounded],
        "error_before": error(0.6, 0.016),
        "error_after": error(0.2, 0.004),
    }


def correction(value, prior_sds):
    return {"value": value, "prior_sds": prior_sds}


class RightCause(unittest.TestCase):
    def test_a_selected_cause_is_right_and_its_shift_error_is_scored(self):
        r = sc.score(ROW, TRUTH, report(["correct I4z"], {"I4z": correction(0.0559, 4.5)}), 1.0)
        self.assertTrue(r["right"])
        self.assertEqual(r["false"], [])
        # Shift fitted 0.0174 of the true 0.01925: an error of 10 %.
        self.assertAlmostEqual(r["parameters"][0]["relative_error"], (0.01925 - 0.0174) / 0.01925, places=9)
        self.assertTrue(r["halved"])

    def test_a_cause_not_separable_from_a_plausible_selected_correction_is_right(self):
        rep = report(["correct I5x"], {"I5x": correction(0.060, 1.4)}, [("correct I5x", "correct I4z")])
        r = sc.score(ROW, TRUTH, rep, 1.0)
        self.assertTrue(r["right"])
        self.assertEqual(r["right_via"], [{"cause": "correct I4z", "not_separable_from": "correct I5x"}])
        self.assertEqual(r["missed_via"], [])
        # The stand-in is the cause's, not one more false cause.
        self.assertEqual(r["false"], [])

    def test_a_cause_not_separable_from_a_selected_correction_beyond_its_prior_is_missed_and_says_so(self):
        rep = report(["correct I5x"], {"I5x": correction(0.0727, 3.9)}, [("correct I5x", "correct I4z")])
        r = sc.score(ROW, TRUTH, rep, 1.0)
        self.assertFalse(r["right"])
        self.assertEqual(r["right_via"], [])
        self.assertEqual(r["missed_via"], [{"cause": "correct I4z", "not_separable_from": "correct I5x"}])
        self.assertEqual(r["false"], ["correct I5x"])
        s = sc.summary([r])
        self.assertEqual((s["right_causes"], s["missed_named_beside_a_correction_beyond_its_prior"]), (0, 1))
        self.assertFalse(s["targets_met"])

    def test_a_cause_nobody_names_is_missed_without_a_stand_in(self):
        r = sc.score(ROW, TRUTH, report(["correct m5"], {"m5": correction(2.0, 1.0)}), 1.0)
        self.assertFalse(r["right"])
        self.assertEqual((r["missed_via"], r["false"]), ([], ["correct m5"]))


class Controls(unittest.TestCase):
    def test_a_control_with_only_the_speed_decay_is_clean_and_any_other_selection_is_false(self):
        control = {"name": "control_a"}
        clean = sc.score(control, TRUTH, report([], {}), 1.0)
        self.assertIsNone(clean["right"])
        self.assertTrue(clean["control_clean"])
        dirty = sc.score(control, TRUTH, report(["steer_damping"], {}), 1.0)
        self.assertFalse(dirty["control_clean"])
        self.assertFalse(sc.summary([clean, dirty])["targets_met"])


if __name__ == "__main__":
    unittest.main()
