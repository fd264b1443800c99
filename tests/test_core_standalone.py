"""The core stands alone: ``import rdmp_gym`` loads none of the optional layers' libraries and changes no environment
variable (checked in a fresh interpreter, where nothing else has loaded them yet)."""

import json
import os
import subprocess
import sys

_PROBE = """
import json, os, sys
before = dict(os.environ)
import rdmp_gym
import rdmp_gym.dmp.fitting, rdmp_gym.dmp.stopping, rdmp_gym.signals.segmentation
import rdmp_gym.figures.paper, rdmp_gym.figures.plots
loaded = sorted({name.split(".")[0] for name in sys.modules} & {"gymnasium", "mujoco", "matplotlib", "torch"})
print(json.dumps({"loaded": loaded, "environ_changed": dict(os.environ) != before,
                  "envs": "rdmp_gym.envs" in sys.modules}))
"""


def _probe() -> dict:
    env = {key: value for key, value in os.environ.items() if key != "MUJOCO_GL"}
    result = subprocess.run([sys.executable, "-c", _PROBE], capture_output=True, text=True, timeout=120, env=env)
    assert result.returncode == 0, result.stderr
    return json.loads(result.stdout.strip().splitlines()[-1])


def test_import_rdmp_gym_loads_no_gymnasium_mujoco_matplotlib_or_torch_and_sets_no_environment_variable():
    found = _probe()
    assert found["loaded"] == []
    assert not found["environ_changed"]
    assert not found["envs"]


def test_the_figures_load_matplotlib_only_when_drawing(tmp_path):
    code = ("import sys; from rdmp_gym.figures.plots import plot_canonical_system; "
            "from rdmp_gym import CanonicalSystem; assert 'matplotlib' not in sys.modules; "
            "import matplotlib; matplotlib.use('Agg'); "
            "plot_canonical_system(CanonicalSystem(period=1.0), [(0.0, 0.5)]).savefig(sys.argv[1])")
    result = subprocess.run([sys.executable, "-c", code, str(tmp_path / "fig.png")], capture_output=True, text=True,
                            timeout=120)
    assert result.returncode == 0, result.stderr
    assert (tmp_path / "fig.png").stat().st_size > 0
