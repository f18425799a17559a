"""The presets: the default is the best measured one on the held-out half of the evaluation."""

import numpy as np
import pytest

from gyrofilter import GyroFilter
from gyrofilter.evaluation import evaluate as E, filters as F
from gyrofilter.filter.presets import DEFAULT_PRESET, PRESETS
from support import RECORDINGS

REC_DIR = str(RECORDINGS)


def test_the_default_preset_is_recommended_and_recommended_is_adaptive_kalman():
    assert DEFAULT_PRESET == "recommended"
    assert GyroFilter(100.0).settings == GyroFilter(100.0, preset="adaptive_kalman").settings
    assert GyroFilter(100.0, preset="paper").settings.guard_blocks == 0  # the faithful filter has no guard
    for name in PRESETS:
        s = GyroFilter(100.0, preset=name).settings
        if name != "paper" and s.tracker == "kalman":
            assert s.guard_blocks > 0, f"Kalman preset {name} without a divergence guard"


def test_the_default_is_no_worse_than_any_other_preset_on_the_held_out_half():
    # 10 s without numba: in the default suite, as "the default is the best filter measured" is its promise
    split = E.HOLDOUT_SPLIT
    specs = [F.FilterSpec(name, "candidate", "", F.gyrofilter_run(name)) for name in PRESETS]
    ev = E.evaluate(specs, recordings_dir=REC_DIR, static_names=split["static"], profiles=split["profiles"],
                    broad_names=split["broad"], with_lag=False)
    assert sorted(ev.static) == sorted(PRESETS) and len(ev.broad_names) == 2 and len(ev.profiles) == 2
    best = DEFAULT_PRESET
    for other in PRESETS:
        for rec, reduction in ev.static[best].items():
            assert np.min(reduction) >= E.PAPER_CLAIM_REDUCTION
            # at rest a tie within 1 % counts: since the rest value after motion starts from the latest half of the
            # constancy window (hold.recent_mean, which a turn under a vibration needed), the default and the hold
            # reduce the worst held-out axis alike, 17.27x and 17.31x (mpu6050_static_449s z; docs/evaluate.md)
            assert np.min(reduction) >= 0.99 * np.min(ev.static[other][rec]), (other, rec)
        for p, d in ev.dynamic[best].items():
            assert d["rmse_dps"] <= ev.dynamic[other][p]["rmse_dps"], (other, p)
        for b, d in ev.broad[best].items():
            assert d["rmse_all_dps"] <= ev.broad[other][b]["rmse_all_dps"], (other, b)


def test_every_preset_is_listed_in_formats_md_and_in_help(capsys):
    """A new preset is a one-file change (filter/presets.py) but for this hand-written list:
    docs/settings.md's table is generated, the --preset choices and the smoother's presets come
    from PRESETS (the new-contributor trial of issue 23 found them typed out in three places)."""
    import re

    from gyrofilter.cli import main
    from gyrofilter.filter.smoother import SMOOTHABLE_PRESETS
    from support import REPO

    formats = (REPO / "docs" / "formats.md").read_text(encoding="utf-8")
    item = formats[formats.index("- Presets ("):formats.index("- With `temp_coefficient_dps_per_c`")]
    assert all(f"`{name}`" in item for name in PRESETS), item
    for command in ("replay", "run"):
        with pytest.raises(SystemExit):
            main([command, "--help"])
        help_text = " ".join(capsys.readouterr().out.split())
        assert re.search(r"--preset \{([^}]*)\}", help_text).group(1).split(",") == sorted(PRESETS)
    assert set(SMOOTHABLE_PRESETS) == {"recommended", "adaptive_kalman"}
