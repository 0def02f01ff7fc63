"""Vendor conventions → canonical frame, and the curve mnemonics table."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from pydantic import ValidationError

from pipeline.io.conventions import Conventions, to_canonical
from pipeline.io.mnemonics import canonical_name, normalise, register_alias
from pipeline.tables import RawSamples

RNG = np.random.default_rng(5)
N = 50


def canonical_table():
    data = {"time": np.arange(N) * 0.01, "frame_angle": RNG.uniform(0, 360, N)}
    for triad in ("gyro", "acc", "mag"):
        for axis in "xyz":
            data[f"{triad}_{axis}"] = RNG.normal(0, 10, N)
    return RawSamples.compiled().make_table(data)


def vendor_view(table, axes, *, specific_force=False, left_hand=False, ccw_frame=False):
    """What a vendor with these conventions would have written (built independently:
    vendor axis j carries ±canonical axis i where axes[i] names ±j)."""
    out = {name: table.column(name).to_numpy().copy() for name in table.column_names}
    for triad in ("gyro", "acc", "mag"):
        for i, spec in enumerate(axes):
            sign = -1.0 if spec.startswith("-") else 1.0
            j = spec.lstrip("+-")
            value = sign * table.column(f"{triad}_{'xyz'[i]}").to_numpy()
            if triad == "acc" and specific_force:
                value = -value
            if triad == "gyro" and left_hand:
                value = -value
            out[f"{triad}_{j}"] = value
    if ccw_frame:
        out["frame_angle"] = np.mod(-out["frame_angle"], 360.0)
    return RawSamples.compiled().make_table(out)


@pytest.mark.parametrize(
    "axes",
    [
        tuple(s + a for s, a in zip(signs, perm, strict=True))
        for perm in itertools.permutations("xyz")
        for signs in [("", "", ""), ("-", "", "-"), ("", "", "-")]
    ],
)
def test_any_signed_permutation_round_trips(axes):
    table = canonical_table()
    conv = Conventions(
        axes=axes,
        accelerometer="specific_force",
        gyro_rotation="left_hand",
        frame_angle_direction="counterclockwise",
    )
    vendor = vendor_view(table, axes, specific_force=True, left_hand=True, ccw_frame=True)
    back = to_canonical(vendor, conv)
    for name in table.column_names:
        np.testing.assert_allclose(
            back.column(name).to_numpy(), table.column(name).to_numpy(), atol=1e-12, err_msg=name
        )
    assert back.schema.field("gyro_x").metadata == table.schema.field("gyro_x").metadata
    assert abs(np.linalg.det(conv.matrix())) == 1.0


def test_left_handed_frame_has_negative_determinant():
    assert np.linalg.det(Conventions(axes=("x", "y", "-z")).matrix()) == -1.0


def test_identity_leaves_table_untouched():
    table = canonical_table()
    assert to_canonical(table, Conventions()) is table


def test_toolface_offset_and_direction():
    import pyarrow as pa

    table = pa.table({"toolface": [10.0, 350.0, 90.0]})
    conv = Conventions(toolface_direction="counterclockwise", toolface_offset=30.0)
    # vendor 30° is the high side; vendor angles grow counterclockwise
    np.testing.assert_allclose(
        to_canonical(table, conv).column("toolface").to_numpy(), [20.0, 40.0, 300.0]
    )


@pytest.mark.parametrize("axes", [("x", "x", "z"), ("x", "y"), ("x", "y", "w"), ("+-x", "y", "z")])
def test_bad_axes_are_refused(axes):
    with pytest.raises(ValidationError, match="axes"):
        Conventions(axes=axes)


def test_permutation_needs_whole_triads():
    table = canonical_table().drop_columns(["mag_y"])
    with pytest.raises(ValueError, match="mag needs columns"):
        to_canonical(table, Conventions(axes=("y", "x", "-z")))


@pytest.mark.parametrize(
    ("name", "canonical"),
    [
        ("DEPT", "md"),
        ("Measured Depth", "md"),
        ("+N/-S", "north"),
        ("E/W", "east"),
        ("INCL", "inc"),
        ("HAZI", "azi"),
        ("GX", "acc_x"),
        ("Gyro_Y", "gyro_y"),
        ("WZ", "gyro_z"),
        ("BZ", "mag_z"),
        ("RB", "toolface"),
        ("ETIM", "time"),
        ("DLS", "dls"),
        ("TVD", "tvd"),
    ],
)
def test_mnemonics(name, canonical):
    assert canonical_name(name) == canonical


def test_ambiguous_names_are_not_guessed_and_aliases_extend():
    assert canonical_name("AZ") is None
    assert normalise(" +N/-S ") == "NS"
    register_alias("ACME_DEPTH_FT", "md")
    assert canonical_name("acme depth ft") == "md"
    with pytest.raises(ValueError, match="already names"):
        register_alias("GX", "gyro_x")
    with pytest.raises(KeyError, match="unknown canonical column"):
        register_alias("X", "nothing")
