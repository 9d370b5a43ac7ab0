"""End-effector parameterizations: conversions against scipy, E against finite differences, singular sets.

Every property runs over every parameterization (all 12 Euler sequences) under hypothesis-drawn seeds and
regimes: random poses, near the identity (θ swept over 0 … π − 1e-6, jaxlie style) and near each singular set
or branch cut. References are independent: scipy's Rotation, central differences along C(t) = exp([ω]x t)·C
or p(t) = p + v t, series of the SO(3) Jacobian, numpy's pinv.
"""

from __future__ import annotations

import os
import warnings
from math import factorial

import numpy as np
import pytest
from finite_differences import assert_close_relative
from hypothesis import assume, given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from kinengine.errors import KinematicsError, ParameterizationError, RepresentationSingularityError
from kinengine.parameterizations import (
    EULER_SEQUENCES,
    POSITION_PARAMETERIZATIONS,
    ROTATION_PARAMETERIZATIONS,
    get_position,
    get_rotation,
)
from kinengine.parameterizations.base import SMALL_ANGLE_SQ

ROTATIONS = sorted(ROTATION_PARAMETERIZATIONS)
POSITIONS = sorted(POSITION_PARAMETERIZATIONS)
EULERS = [f"euler_{seq}" for seq in EULER_SEQUENCES]
SWEEP = (0.0, 1e-12, 1e-9, 1e-7, 1e-5, 1e-3, 1.0, np.pi - 1e-6)
REDUNDANT = {"quaternion", "angle_axis", "rotation_matrix"}
PROPERTY = settings(
    max_examples=int(os.environ.get("KINENGINE_PROPERTY_EXAMPLES", "30")), deadline=None, derandomize=True
)
seeds = st.integers(0, 2**32 - 1)
rotation_regimes = st.sampled_from(["random", "near_identity", "near_singular"])
position_regimes = st.sampled_from(["random", "near_singular"])


def lookup(name):
    return POSITION_PARAMETERIZATIONS.get(name) or ROTATION_PARAMETERIZATIONS[name]


def wrap(angle):
    return (np.asarray(angle) + np.pi) % (2 * np.pi) - np.pi


def unit(rng):
    v = rng.normal(size=3)
    return v / np.linalg.norm(v)


def exp_so3(rotvec):
    return Rotation.from_rotvec(rotvec).as_matrix()


def sample_rotation(name, regime, rng):
    """C_IE in a regime; near_singular: near the singular set (Euler, angle-axis) or the branch cut θ = π."""
    if regime == "random":
        return Rotation.random(rng=rng).as_matrix()
    if regime == "near_identity":
        return exp_so3(SWEEP[rng.integers(len(SWEEP))] * unit(rng))
    delta = SWEEP[rng.integers(6)] * rng.choice([-1.0, 1.0])  # 0 … 1e-3 from the set
    if name.startswith("euler"):
        seq = name[-3:]
        lock = rng.choice([-np.pi / 2, np.pi / 2]) if seq[0] != seq[2] else rng.choice([0.0, np.pi])
        chi = [rng.uniform(-np.pi, np.pi), lock + delta, rng.uniform(-np.pi, np.pi)]
        return Rotation.from_euler(seq.upper(), chi).as_matrix()
    return exp_so3((abs(delta) if name == "angle_axis" else np.pi - abs(delta)) * unit(rng))


def sample_position(regime, rng):
    if regime == "random":
        return rng.normal(size=3)
    rho, alpha = SWEEP[rng.integers(6)], rng.uniform(-np.pi, np.pi)  # 0 … 1e-3 from the z axis
    return np.array([rho * np.cos(alpha), rho * np.sin(alpha), rng.normal()])


def quiet(function, *args):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return function(*args)


def branch_margin(name, C):
    """Distance of θ(C) from the branch cut θ = π of the parameterizations that have one."""
    if name in ("quaternion", "angle_axis", "rotation_vector"):
        return np.pi - np.linalg.norm(Rotation.from_matrix(C).as_rotvec())
    return np.inf


def moving_sample(name, regime, seed, step=1e-3):
    """(param, χ(t), u, h, distance): χ along p + u t or exp([u]x t)·C and a central-difference step h that
    stays on one side of singular sets and branch cuts (h <= step·distance).

    Positions read the regime "near_identity" as "random".
    """
    rng = np.random.default_rng(seed)
    if name in POSITION_PARAMETERIZATIONS:
        regime = "random" if regime == "near_identity" else regime
        param, p0, u = get_position(name), sample_position(regime, rng), rng.normal(size=3)

        def chi_at(t):
            return quiet(param.from_position, p0 + u * t)

        margin = np.inf
    else:
        param, C0, u = get_rotation(name), sample_rotation(name, regime, rng), rng.normal(size=3)

        def chi_at(t):
            return quiet(param.from_rotation, exp_so3(u * t) @ C0)

        margin = branch_margin(name, C0)
    distance = param.singularity_distance(chi_at(0.0))
    h = min(1e-6, step * distance, 0.25 * margin) / np.linalg.norm(u)
    return param, chi_at, u, h, distance


# -- registry and attributes --------------------------------------------------------------------------
def test_registry_holds_every_family_and_all_12_euler_sequences():
    assert POSITIONS == ["cartesian", "cylindrical", "spherical"]
    assert set(ROTATIONS) == set(EULERS) | {"quaternion", "angle_axis", "rotation_vector", "rotation_matrix"}
    for name in POSITIONS + ROTATIONS:
        p = lookup(name)
        assert p.name == name and p.size == len(p.labels) and p.singular_set
        assert p.kind == ("position" if name in POSITIONS else "rotation")
    sizes = {"quaternion": 4, "angle_axis": 4, "rotation_vector": 3, "rotation_matrix": 9}
    assert all(get_rotation(n).size == sizes.get(n, 3) for n in ROTATIONS)
    for pos in POSITIONS:  # labels stay unique in any (position, rotation) pair
        for rot in ROTATIONS:
            labels = get_position(pos).labels + get_rotation(rot).labels
            assert len(set(labels)) == len(labels)


def test_unknown_names_raise_listing_the_valid_ones():
    with pytest.raises(ParameterizationError, match="euler_zyz") as info:
        get_rotation("euler_abc")
    assert isinstance(info.value, KinematicsError)
    with pytest.raises(ParameterizationError, match="cylindrical"):
        get_position("polar")


@pytest.mark.parametrize(
    ("value", "message"),
    [
        ([0.1 + 2j, 0.0, 0.0], r"`chi` to be real numbers, got complex"),  # numpy would drop 2j silently
        (["a", 0.0, 0.0], r"`chi` to be an array of real numbers"),
        ([[0.1, 0.2], [0.3]], r"`chi` to be an array of real numbers"),
        ([None, 0.0, 0.0], r"`chi` to be an array of real numbers"),  # numpy would make NaN
        (np.array([1, 2, 3], dtype="datetime64[s]"), r"`chi` to be real numbers, got datetime64"),
        ([10**400, 0, 0], r"`chi` to be an array of real numbers"),  # beyond float range
    ],
)
def test_values_that_are_not_real_numbers_are_refused(value, message):
    for method in ("E", "to_rotation"):
        with pytest.raises(ParameterizationError, match=message):
            getattr(get_rotation("euler_zyx"), method)(value)
    with pytest.raises(ParameterizationError, match=r"`C` to be real numbers"):
        get_rotation("rotation_vector").from_rotation(np.eye(3) * (1 + 0j))


def test_wrong_shapes_name_the_argument_and_the_shape():
    with pytest.raises(ParameterizationError, match=r"`chi`.*\(3,\).*got \(4,\)"):
        get_rotation("euler_zyx").E(np.zeros(4))
    with pytest.raises(ParameterizationError, match=r"`C`.*got \(3, 4\)"):
        get_rotation("quaternion").from_rotation(np.zeros((3, 4)))
    with pytest.raises(ParameterizationError, match="`velocity`"):
        get_position("spherical").E_dot(np.ones(3), np.ones(2))
    zyz = get_rotation("euler_zyz")  # lists and other dtypes take the general path, same values
    np.testing.assert_allclose(zyz.E([0.1, 0.2, 0.3]), zyz.E(np.array([0.1, 0.2, 0.3])), rtol=1e-15, atol=0)
    quarter_turn = np.array([[0, -1, 0], [1, 0, 0], [0, 0, 1]], dtype=np.float32)
    np.testing.assert_allclose(
        zyz.from_rotation(quarter_turn, warn=False), [np.pi / 2, 0, 0], rtol=0, atol=1e-15
    )


# -- conversions -------------------------------------------------------------------------------------
def scipy_parameters(name, C):
    r = Rotation.from_matrix(C)
    if name.startswith("euler"):
        return quiet(r.as_euler, name[-3:].upper())
    if name == "quaternion":
        return r.as_quat(canonical=True)[..., [3, 0, 1, 2]]
    if name == "rotation_matrix":
        return C.reshape(C.shape[:-2] + (9,))
    rotvec = r.as_rotvec()
    if name == "rotation_vector":
        return rotvec
    theta = np.linalg.norm(rotvec, axis=-1, keepdims=True)
    axis = np.where(theta > 0, rotvec / np.where(theta > 0, theta, 1.0), [1.0, 0.0, 0.0])  # x at θ = 0
    return np.concatenate([theta, axis], axis=-1)


@pytest.mark.parametrize("name", ROTATIONS)
@PROPERTY
@given(seed=seeds, regime=rotation_regimes)
def test_from_rotation_matches_scipy_and_round_trips(name, seed, regime):
    rng = np.random.default_rng(seed)
    param = get_rotation(name)
    C = sample_rotation(name, regime, rng)
    chi = quiet(param.from_rotation, C)
    # C -> χ -> C everywhere (at gimbal lock, within scipy's 1e-7 tolerance on χ2, χ3 = 0 costs up to ~1e-7)
    locked = name.startswith("euler") and param.singularity_distance(chi) < 2e-7
    np.testing.assert_allclose(param.to_rotation(chi), C, rtol=0, atol=3e-7 if locked else 1e-14)
    expected = scipy_parameters(name, C)
    theta = np.linalg.norm(Rotation.from_matrix(C).as_rotvec())
    if param.singularity_distance(chi) > 1e-3 and np.pi - theta > 1e-9:  # χ unique and well conditioned
        delta = wrap(chi - expected) if name.startswith("euler") else chi - expected
        np.testing.assert_allclose(delta, 0.0, rtol=0, atol=1e-12)
        # χ -> C -> χ
        delta = param.from_rotation(param.to_rotation(chi)) - chi
        delta = wrap(delta) if name.startswith("euler") else delta
        np.testing.assert_allclose(delta, 0.0, rtol=0, atol=1e-12)
    else:  # degenerate: compare through matrices
        np.testing.assert_allclose(param.to_rotation(chi), param.to_rotation(expected), rtol=0, atol=3e-7)


@pytest.mark.parametrize("name", POSITIONS)
@PROPERTY
@given(seed=seeds, regime=position_regimes)
def test_from_position_matches_the_definition_and_round_trips(name, seed, regime):
    pos = sample_position(regime, np.random.default_rng(seed))
    param = get_position(name)
    chi = quiet(param.from_position, pos)
    x, y, z = pos
    expected = {
        "cartesian": pos,
        "cylindrical": [np.hypot(x, y), np.arctan2(y, x), z],
        "spherical": [np.linalg.norm(pos), np.arctan2(y, x), chi[2]],
    }[name]
    np.testing.assert_allclose(chi, expected, rtol=0, atol=1e-13)
    if name == "spherical":  # the polar angle φ ∈ [0, π] from +z: r sin φ = ρ, r cos φ = z
        assert 0 <= chi[2] <= np.pi
        np.testing.assert_allclose(
            chi[0] * np.array([np.sin(chi[2]), np.cos(chi[2])]),
            [np.hypot(x, y), z],
            rtol=0,
            atol=1e-15 * max(1.0, chi[0]),
        )
    np.testing.assert_allclose(param.to_position(chi), pos, rtol=0, atol=1e-14)


# -- E, E_inverse, E_dot ------------------------------------------------------------------------------
@pytest.mark.parametrize("name", POSITIONS + ROTATIONS)
@PROPERTY
@given(seed=seeds, regime=st.sampled_from(["random", "near_identity", "near_singular"]))
def test_E_matches_finite_differences_of_chi(name, seed, regime):
    param, chi_at, u, h, distance = moving_sample(name, regime, seed)
    assume(distance >= 1e-5 and h >= 1e-8)  # closer, χ(C) itself is ill-conditioned (error ~ eps/distance)
    fd = wrap(chi_at(h) - chi_at(-h)) / (2 * h)
    assert_close_relative(param.E(chi_at(0.0)) @ u, fd, 1e-6, name)


@pytest.mark.parametrize("name", POSITIONS + ROTATIONS)
@PROPERTY
@given(seed=seeds, regime=st.sampled_from(["random", "near_identity", "near_singular"]))
def test_E_dot_matches_finite_differences_of_E(name, seed, regime):
    param, chi_at, u, h, distance = moving_sample(name, regime, seed, step=1e-4)  # Ė ~ 1/distance²
    assume(distance >= 1e-3 and h >= 1e-8)
    fd = (param.E(chi_at(h)) - param.E(chi_at(-h))) / (2 * h)
    assert_close_relative(param.E_dot(chi_at(0.0), u), fd, 1e-6, name)


@pytest.mark.parametrize("name", POSITIONS + ROTATIONS)
@PROPERTY
@given(seed=seeds, regime=st.sampled_from(["random", "near_identity", "near_singular"]))
def test_E_inverse_inverts_E(name, seed, regime):
    param, chi_at, _, _, distance = moving_sample(name, regime, seed)
    chi = chi_at(0.0)
    assume(distance >= 1e-6)
    E, E_inverse = param.E(chi), param.E_inverse(chi)
    np.testing.assert_allclose(E_inverse @ E, np.eye(3), rtol=0, atol=1e-12 / min(1.0, distance))
    if name in REDUNDANT:  # the Moore–Penrose pseudo-inverse, computed independently
        np.testing.assert_allclose(E_inverse, np.linalg.pinv(E), rtol=0, atol=1e-13 / min(1.0, distance))
    else:
        np.testing.assert_allclose(E @ E_inverse, np.eye(3), rtol=0, atol=1e-12 / min(1.0, distance))


@pytest.mark.parametrize("name", EULERS)
def test_euler_E_inverse_is_the_basis_of_the_rotation_axes(name):
    # ω = e_a χ̇1 + R_a(χ1) e_b χ̇2 + R_a(χ1) R_b(χ2) e_c χ̇3, each axis from scipy
    seq, rng = name[-3:], np.random.default_rng(7)
    param, axes = get_rotation(name), {"x": 0, "y": 1, "z": 2}
    for chi in rng.uniform(-3, 3, size=(5, 3)):
        first = Rotation.from_euler(seq[0].upper(), chi[0]).as_matrix()
        second = first @ Rotation.from_euler(seq[1].upper(), chi[1]).as_matrix()
        B = np.column_stack([np.eye(3)[axes[seq[0]]], first[:, axes[seq[1]]], second[:, axes[seq[2]]]])
        np.testing.assert_allclose(param.E_inverse(chi), B, rtol=0, atol=1e-15)
        np.testing.assert_allclose(param.E(chi), np.linalg.inv(B), rtol=0, atol=1e-10)


def left_jacobian_series(phi, terms=40):
    """J_l(φ) = Σ [φ]x^k / (k + 1)!: an independent reference for the rotation vector's E_inverse and E."""
    K = np.array([[0, -phi[2], phi[1]], [phi[2], 0, -phi[0]], [-phi[1], phi[0], 0]])
    out, power = np.zeros((3, 3)), np.eye(3)
    for k in range(terms):
        out, power = out + power / factorial(k + 1), power @ K
    return out


@pytest.mark.parametrize(
    "theta",
    SWEEP
    + (
        np.sqrt(SMALL_ANGLE_SQ) * (1 - 1e-12),
        np.sqrt(SMALL_ANGLE_SQ),
        np.sqrt(SMALL_ANGLE_SQ) * (1 + 1e-12),
        2.5,
    ),
)
def test_rotation_vector_maps_match_the_series_across_the_taylor_branch(theta):
    param, rng = get_rotation("rotation_vector"), np.random.default_rng(3)
    phi, u = theta * unit(rng), rng.normal(size=3)
    J = left_jacobian_series(phi)
    np.testing.assert_allclose(param.E_inverse(phi), J, rtol=0, atol=1e-15)
    np.testing.assert_allclose(param.E_inverse(phi[None])[0], J, rtol=0, atol=1e-15)
    np.testing.assert_allclose(param.E(phi), np.linalg.inv(J), rtol=0, atol=2e-15)
    np.testing.assert_allclose(param.to_rotation(phi), exp_so3(phi), rtol=0, atol=1e-15)
    h = 1e-6  # E_dot where the closed form would cancel catastrophically: against a difference of the series
    fd = (
        np.linalg.inv(left_jacobian_series(phi + h * param.E(phi) @ u))
        - np.linalg.inv(left_jacobian_series(phi - h * param.E(phi) @ u))
    ) / (2 * h)
    np.testing.assert_allclose(param.E_dot(phi, u), fd, rtol=0, atol=1e-9)


# -- singular sets -----------------------------------------------------------------------------------
def on_and_near_the_singular_set(name, delta, rng):
    """χ at distance ~delta from the singular set (delta = 0: on it)."""
    if name == "cylindrical":
        return np.array([delta, rng.uniform(-3, 3), rng.normal()])
    if name == "spherical":
        return np.array([1.5, rng.uniform(-3, 3), delta])
    if name == "angle_axis":
        return np.concatenate([[delta], unit(rng)])
    if name == "rotation_vector":
        return (2 * np.pi - delta) * unit(rng)
    seq = name[-3:]
    chi2 = (np.pi / 2 - delta) if seq[0] != seq[2] else delta
    return np.array([rng.uniform(-3, 3), chi2, rng.uniform(-3, 3)])


SINGULAR = ["cylindrical", "spherical", "angle_axis", "rotation_vector"] + EULERS


@pytest.mark.parametrize("name", SINGULAR)
def test_singularity_distance_vanishes_on_the_set_and_E_grows_like_its_inverse(name):
    param = lookup(name)
    rng = np.random.default_rng(11)
    assert param.singularity_distance(on_and_near_the_singular_set(name, 0.0, rng)) <= 1e-15
    growth = []
    for delta in (1e-2, 1e-4, 1e-6, 1e-8):
        chi = on_and_near_the_singular_set(name, delta, rng)
        distance = param.singularity_distance(chi)
        assert 0.4 * delta <= distance <= 1.6 * delta  # ~ the vanishing sine / radius / angle
        growth.append(np.linalg.norm(param.E(chi)) * distance)
    assert max(growth) <= 10 * min(growth) and min(growth) > 0.1  # ‖E‖ ~ 1/distance


@pytest.mark.parametrize("name", ["cartesian", "quaternion", "rotation_matrix"])
def test_never_singular_parameterizations_report_infinite_distance(name):
    param = lookup(name)
    chi = param.from_position(np.zeros(3)) if param.kind == "position" else param.from_rotation(np.eye(3))
    assert param.singularity_distance(chi) == np.inf
    assert np.all(param.singularity_distance(np.stack([chi, chi])) == np.inf)
    assert np.linalg.norm(param.E(chi)) < 3


@pytest.mark.parametrize(
    "name, chi",
    [
        ("cylindrical", [0.0, 1.0, 2.0]),
        ("spherical", [0.0, 1.0, 1.0]),
        ("angle_axis", [0.0, 0.0, 0.0, 1.0]),
        ("euler_zyz", [0.3, 0.0, 0.2]),
    ],
)
def test_E_exactly_on_the_singular_set_raises_with_alternatives(name, chi):
    param = lookup(name)
    for batch in (np.array(chi), np.array([chi, chi])):
        with pytest.raises(RepresentationSingularityError) as info:
            param.E(batch)
        assert info.value.parameterization == name and info.value.alternatives
    assert np.all(np.isfinite(param.E_inverse(np.array(chi))))


@pytest.mark.parametrize("name", EULERS)
@pytest.mark.parametrize("offset", [0.0, 1e-9, -5e-8])
def test_gimbal_lock_warns_like_scipy_and_still_returns_valid_angles(name, offset):
    seq, param = name[-3:], get_rotation(name)
    lock = np.pi / 2 if seq[0] != seq[2] else 0.0
    C = Rotation.from_euler(seq.upper(), [0.4, lock + offset, -1.1]).as_matrix()
    with pytest.warns(UserWarning, match="gimbal lock"):
        chi = param.from_rotation(C)
    with pytest.warns(UserWarning):
        expected = Rotation.from_matrix(C).as_euler(seq.upper())
    assert chi[2] == 0.0 and np.all(np.abs(chi) <= np.pi)
    np.testing.assert_allclose(wrap(chi - expected), 0.0, rtol=0, atol=1e-6)
    np.testing.assert_allclose(param.to_rotation(chi), C, rtol=0, atol=1e-7)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        np.testing.assert_array_equal(param.from_rotation(C, warn=False), chi)


def test_angle_axis_at_the_identity_warns_at_the_callers_line_and_picks_the_x_axis():
    with pytest.warns(UserWarning, match="axis") as record:
        chi = get_rotation("angle_axis").from_rotation(np.eye(3))
    assert record[0].filename == __file__
    np.testing.assert_array_equal(chi, [0.0, 1.0, 0.0, 0.0])


def test_branch_cut_at_pi_follows_scipys_canonical_sign():
    C = np.diag([-1.0, 1.0, -1.0])  # a half turn about y: w = 0, first nonzero of (x, y, z) positive
    np.testing.assert_array_equal(get_rotation("quaternion").from_rotation(C), [0.0, 0.0, 1.0, 0.0])
    rotvec, angle_axis = get_rotation("rotation_vector"), get_rotation("angle_axis")
    np.testing.assert_allclose(rotvec.from_rotation(C), [0, np.pi, 0], rtol=0, atol=1e-15)
    np.testing.assert_allclose(angle_axis.from_rotation(C), [np.pi, 0, 1, 0], rtol=0, atol=1e-15)


# -- batches -----------------------------------------------------------------------------------------
@pytest.mark.parametrize("name", POSITIONS + ROTATIONS)
@pytest.mark.parametrize("batch", [(5,), (2, 3)])
def test_batched_calls_equal_per_sample_calls(name, batch):
    rng = np.random.default_rng(5)
    param = lookup(name)
    if param.kind == "position":
        convert, back, regimes = param.from_position, param.to_position, ["random", "near_singular"]

        def draw(regime):
            return sample_position(regime, rng)
    else:
        convert, back = (lambda C: quiet(param.from_rotation, C)), param.to_rotation
        regimes = ["near_identity", "random", "near_singular"]  # Taylor branches and closed forms mixed

        def draw(regime):
            return sample_rotation(name, regime, rng)

    n, inputs = int(np.prod(batch)), []
    while len(inputs) < n:  # E is finite for every sample (distance > 0), however large
        x = draw(regimes[len(inputs) % len(regimes)])
        if param.singularity_distance(convert(x)) > 1e-9:
            inputs.append(x)
    inputs = np.array(inputs)
    chi, u = convert(inputs.reshape(batch + inputs.shape[1:])), rng.normal(size=batch + (3,))
    assert chi.shape == batch + (param.size,)
    batched = {
        "chi": chi,
        "back": back(chi),
        "E": param.E(chi),
        "E_inverse": param.E_inverse(chi),
        "E_dot": param.E_dot(chi, u),
        "distance": param.singularity_distance(chi),
    }
    for i, x in enumerate(inputs):  # each method on the same input (near a singular set E amplifies 1 ulp)
        c, ui = chi.reshape(n, -1)[i].copy(), u.reshape(n, 3)[i]
        single = {
            "chi": convert(x),
            "back": back(c),
            "E": param.E(c),
            "E_inverse": param.E_inverse(c),
            "E_dot": param.E_dot(c, ui),
            "distance": param.singularity_distance(c),
        }
        for key, value in single.items():
            got = batched[key].reshape((n,) + np.shape(value))[i]
            np.testing.assert_allclose(got, value, rtol=1e-13, atol=1e-14, err_msg=f"{name} {key}")


def test_unknown_euler_sequence_is_a_parameterization_error():
    from kinengine.parameterizations.euler import EulerAngles

    with pytest.raises(ParameterizationError, match="Expected `seq` to be one of xyz"):
        EulerAngles("xyy")


@pytest.mark.parametrize("name", ROTATIONS)
@PROPERTY
@given(seed=seeds, theta=st.sampled_from([1e-3, 0.5, 1.0, 2.0, 2.8, 3.0]) | st.floats(1e-3, 3.0))
def test_chart_is_the_rate_of_chi_by_central_differences(name, seed, theta):
    """``chart(C)`` (the analytic Jacobian's and the Task's single-pose χ, distance and E_R) gives χ of
    from_rotation, its distance, and an E_R that maps ω to χ̇: (χ(exp([ω]x h) C) − χ(exp(−[ω]x h) C)) / 2h."""
    param = ROTATION_PARAMETERIZATIONS[name]
    rng = np.random.default_rng(seed)
    axis = rng.normal(size=3)
    C = Rotation.from_rotvec(theta * axis / np.linalg.norm(axis)).as_matrix()
    found = param.chart(*C.ravel().tolist())
    chi = param.from_rotation(C, warn=False)
    if found is None:  # only at gimbal lock or where E has no finite value
        assert param.singularity_distance(chi) < 1e-6
        return
    assert_close_relative(np.array(found[0]), chi, 1e-14)
    distance, E = found[1], np.reshape(found[2], (param.size, 3))
    assume(distance > 1e-2)  # E's entries ~ 1/distance: keep the difference quotient accurate
    assert distance == pytest.approx(param.singularity_distance(chi), rel=1e-12, abs=1e-15)
    omega, h = rng.normal(size=3), 1e-6
    ahead = param.from_rotation(Rotation.from_rotvec(h * omega).as_matrix() @ C, warn=False)
    behind = param.from_rotation(Rotation.from_rotvec(-h * omega).as_matrix() @ C, warn=False)
    assume(np.abs(ahead - behind).max() < 1e-3)  # no branch cut crossed (angle wrap, quaternion sign)
    assert_close_relative(E @ omega, (ahead - behind) / (2 * h), 1e-6)


@pytest.mark.parametrize("name", EULERS)
@pytest.mark.parametrize("offset", [0.0, 5e-8, 2e-7, 1e-3])
def test_euler_chart_declines_where_from_rotation_sees_gimbal_lock(name, offset):
    """The single-pose chart gives None exactly where from_rotation warns of gimbal lock (χ2 within scipy's
    1e-7 rad of the singular value), else from_rotation's χ, the distance |cos χ2| (Tait–Bryan) or |sin χ2|
    (proper) and E(χ); and χ reproduces C."""
    param = ROTATION_PARAMETERIZATIONS[name]
    proper = name[6] == name[8]
    chi2 = offset if proper else np.pi / 2 - offset  # at (0) or near the singular set
    C = param.to_rotation([0.4, chi2, -0.7])
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        chi = param.from_rotation(C)
    found = param.chart(*C.ravel().tolist())
    assert (found is None) == (len(caught) == 1)
    assert (found is None) == (offset < 1e-7)
    if found is not None:
        np.testing.assert_allclose(found[0], chi, rtol=0, atol=1e-15)
        expected = abs(np.sin(chi[1])) if proper else abs(np.cos(chi[1]))
        assert found[1] == pytest.approx(expected, rel=1e-12)
        np.testing.assert_allclose(np.reshape(found[2], (3, 3)), param.E(chi), rtol=1e-13, atol=1e-13)
    np.testing.assert_allclose(param.to_rotation(chi), C, rtol=0, atol=3e-7 if offset < 1e-6 else 1e-14)
