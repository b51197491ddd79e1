"""Presets (cistrack.interfaces.preset): a component with other defaults, a component-valued
parameter fixed to a component built from the preset's own parameters, or parameters fixed
outright; what `cistrack plugins` documents is the preset's own signature."""
from __future__ import annotations

import pickle

import pytest

from cistrack.errors import ParameterError
from cistrack.interfaces.component import Component, check_positive
from cistrack.interfaces.preset import preset, preset_defaults
from cistrack.plugin.param_docs import param_docs


class Spring(Component):
    """A spring.

    Parameters
    ----------
    stiffness : float
        Force per unit stretch (must be positive).
    """

    kind = "range-prior"
    registry_name = "spring"

    def __init__(self, stiffness: float = 1.0):
        self.stiffness = check_positive(self, "stiffness", stiffness)


class Cart(Component):
    """A cart on a spring.

    Parameters
    ----------
    spring : Spring or None
        What pulls the cart.
    mass : float
        The cart's mass.
    brake : bool
        Whether the brake is on.
    """

    kind = "range-prior"

    def __init__(self, spring: Spring | None = None, mass: float = 2.0, brake: bool = False):
        self.spring = spring
        self.mass = check_positive(self, "mass", mass)
        self.brake = brake


HeavyCart = preset(Cart, "HeavyCart", "A heavy cart.", mass=50.0)
SpringCart = preset(Cart, "SpringCart", "A cart on its own spring, brake off.",
                    nested={"spring": (Spring, ("stiffness",))}, fixed={"brake": False}, stiffness=3.0)


def test_a_preset_changes_only_the_defaults_it_names():
    assert HeavyCart().get_params() == Cart(mass=50.0).get_params()
    assert HeavyCart(mass=1.0).mass == 1.0
    assert [(p.name, p.default) for p in param_docs(HeavyCart)] == [("spring", None), ("mass", 50.0), ("brake", False)]
    assert preset_defaults(HeavyCart) == {"mass": 50.0} and preset_defaults(Cart) == {}


def test_a_preset_validates_as_its_base_does():
    with pytest.raises(ParameterError, match="mass"):
        HeavyCart(mass=-1.0)


def test_a_nested_parameter_becomes_the_presets_own_with_its_meaning():
    docs = {p.name: p for p in param_docs(SpringCart)}
    assert list(docs) == ["mass", "stiffness"]
    assert (docs["stiffness"].default, docs["stiffness"].meaning) == (3.0, "Force per unit stretch (must be positive).")
    cart = SpringCart(stiffness=5.0)
    assert isinstance(cart.spring, Spring) and cart.spring.stiffness == 5.0 and cart.stiffness == 5.0


def test_a_nested_components_error_names_the_preset():
    with pytest.raises(ParameterError, match="SpringCart.*stiffness"):
        SpringCart(stiffness=0.0)


def test_a_fixed_parameter_is_not_the_presets():
    assert SpringCart().brake is False
    with pytest.raises(TypeError, match="brake"):
        SpringCart(brake=True)


@pytest.mark.parametrize("cls", [HeavyCart, SpringCart])
def test_a_presets_instances_rebuild_from_their_params_and_pickle(cls):
    c = cls()
    assert type(c)(**c.get_params()).get_params() == c.get_params()
    assert pickle.loads(pickle.dumps(c)).get_params() == c.get_params()


def test_a_preset_naming_an_unknown_parameter_is_refused():
    with pytest.raises(TypeError, match="no parameters.*weight"):
        preset(Cart, "Bad", "Bad.", weight=1.0)
    with pytest.raises(TypeError, match="no parameter 'elasticity'"):
        preset(Cart, "Bad", "Bad.", nested={"spring": (Spring, ("elasticity",))})
