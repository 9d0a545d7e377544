"""Component plugins: a module named by the plant file (imported with the user's
opt-in, ``allow_import=True``), and name clashes."""

from pathlib import Path

import numpy as np
import pytest

from dnasim.core.errors import PlantError
from dnasim.plant.plantfile import load

ROOT = Path(__file__).resolve().parent.parent

# a user's component: a square-root valve whose flow is scaled by a fixed factor
PLUGIN = '''
from dnasim.library import Param, Valve


class {cls}(Valve):
    """A valve with a fixed opening given as a parameter (no signal input)."""

    PARAMS = tuple(p for p in Valve.PARAMS if p.name != "opening") + (
        Param("fixed_opening", "1", 1.0, "the valve's opening", min=0.0, max=1.0),
    )

    def setup(self):
        self.params["opening"] = self.params["fixed_opening"]
        super().setup()
'''


def plant_with(tmp_path, module, cls):
    (tmp_path / f"{module}.py").write_text(PLUGIN.format(cls=cls))
    text = (ROOT / "plants" / "air_pipe.toml").read_text()
    text = text.replace('medium = "Air"', f'medium = "Air"\nimport = ["{module}"]', 1)
    text = text.replace('type = "Valve"', f'type = "{cls}"').replace(
        "opening = 1\n", "fixed_opening = 0.5\n"
    )
    path = tmp_path / "plant.toml"
    path.write_text(text)
    return path


def test_plugin_component_from_a_plant_file(tmp_path):
    loaded = load(plant_with(tmp_path, "my_components_a", "HalfValve"), allow_import=True)
    assert type(loaded.plant.components["valve"]).__name__ == "HalfValve"
    assert loaded.spec.imports == ["my_components_a"]
    res = loaded.plant.simulate(t_end=60.0)
    assert res.success
    # the same plant with the library valve at opening 0.5 gives the same run, to
    # round-off (the plugin only renames the opening)
    text = (
        (ROOT / "plants" / "air_pipe.toml").read_text().replace("opening = 1\n", "opening = 0.5\n")
    )
    (tmp_path / "ref.toml").write_text(text)
    ref = load(tmp_path / "ref.toml").plant.simulate(t_end=60.0)
    np.testing.assert_allclose(res["pipe.T_out"], ref["pipe.T_out"], rtol=1e-12)


def test_a_name_clash_is_an_error(tmp_path):
    with pytest.raises(PlantError, match="clashes with 'Pipe'"):
        load(plant_with(tmp_path, "my_components_b", "Pipe"), allow_import=True)


def test_an_unknown_module_is_located(tmp_path):
    text = (ROOT / "plants" / "air_pipe.toml").read_text()
    text = text.replace('medium = "Air"', 'medium = "Air"\nimport = ["no_such_module_x"]', 1)
    (tmp_path / "p.toml").write_text(text)
    with pytest.raises(PlantError, match=r"\[plant\], key 'import'.*no module 'no_such_module_x'"):
        load(tmp_path / "p.toml", allow_import=True)
