"""Well metadata merged and agreed: a survey date stated alone is the one date (a file's
last day goes with it), survey dates out of order are refused, and the headers of several
inputs keep a survey's range whichever is merged last."""

from __future__ import annotations

import datetime as dt
import itertools

import pytest

from pipeline.errors import ParameterError
from pipeline.well import AGREEING, WellMetadata, agreed
from tests_support import ROOT, gyropipe_cli

FIRST, LAST = dt.date(2025, 2, 10), dt.date(2026, 3, 2)
RANGE = WellMetadata(survey_date=FIRST, survey_date_last=LAST)  # a WITSML of several days


def test_a_survey_date_merged_alone_is_the_one_date():
    for day in (FIRST, LAST, dt.date(2026, 6, 1)):
        merged = RANGE.merged({"survey_date": day})
        assert (merged.survey_date, merged.survey_date_last) == (day, None)
        assert merged.survey_dates() == day.isoformat()
    later = RANGE.merged({"survey_date_last": dt.date(2026, 4, 1)})
    assert later.survey_dates() == "2025-02-10 to 2026-04-01"
    assert RANGE.merged({"well": "A-1"}).survey_date_last == LAST
    assert "survey_date_last" not in RANGE.merged({"survey_date": FIRST}).model_dump()


def test_survey_dates_out_of_order_are_refused():
    with pytest.raises(ParameterError, match="survey_date_last 2025-01-01 is before survey_date"):
        RANGE.merged({"survey_date_last": dt.date(2025, 1, 1)})
    with pytest.raises(ValueError, match="survey_date_last 2025-02-09 is before survey_date"):
        WellMetadata(survey_date=FIRST, survey_date_last=dt.date(2025, 2, 9))
    assert WellMetadata(survey_date=FIRST, survey_date_last=FIRST).survey_date_last == FIRST


def test_headers_of_the_range_s_first_day_keep_the_range():
    """A WITSML survey of several days and a CSV run of its first day: the run's well (the
    headers merged, then agreed, as the runner does) states the range in either order."""
    one_day = WellMetadata(survey_date=FIRST)
    for order in itertools.permutations({"witsml": RANGE, "csv": one_day}.items()):
        headers = dict(order)
        merged = WellMetadata()
        for header in headers.values():
            merged = merged.merged(header)
        update, differ = agreed(headers)
        assert merged.merged(update).survey_dates() == "2025-02-10 to 2026-03-02"
        assert differ == {}  # one file states a last day: no difference


def test_numbers_agree_within_their_field_s_tolerance():
    """A latitude 1e-7° apart, a field 0.009 nT, an elevation 0.9 mm: one value; a field
    0.02 nT apart and names differing in case differ; dates compare exactly."""
    a = WellMetadata(well="J-12", latitude=61.25, magnetic_field=50000.0, elevation=54.3)
    b = WellMetadata(well="j-12", latitude=61.2500001, magnetic_field=50000.009, elevation=54.3009)
    update, differ = agreed({"a": a, "b": b})
    assert differ == {"well": {"a": "J-12", "b": "j-12"}}
    assert update.model_dump(exclude_unset=True) == {"well": None}
    c = b.model_copy(update={"magnetic_field": 50000.02, "survey_date": FIRST})
    _, differ = agreed({"a": a.model_copy(update={"survey_date": LAST}), "c": c})
    assert set(differ) == {"well", "magnetic_field", "survey_date"}


def test_every_number_field_has_a_tolerance():
    numbers = {
        name
        for name, field in WellMetadata.model_fields.items()
        if "float" in str(field.annotation)
    }
    assert numbers == set(AGREEING)


@pytest.mark.parametrize("value", [0, 86400.0, "0", "1772409600", " 20260302 "])
def test_a_number_is_no_survey_date(value: object):
    """Pydantic's lax dates read a number as a Unix time: 0 was 1970-01-01, '1772409600'
    2026-03-02 (a declination by that date's model); a date is written as one."""
    for name in ("survey_date", "survey_date_last"):
        with pytest.raises(ValueError, match=f"{value!r} is a number, not a date"):
            WellMetadata.model_validate({name: value})


def test_the_cli_refuses_a_number_for_a_survey_date(tmp_path):
    listing = ROOT / "examples" / "stations-j-well.csv"
    result = gyropipe_cli(
        "run", ROOT / "pipelines" / "survey.yaml", "--input", f"stations={listing}",
        "--well", "survey_date_last=0", "--out", tmp_path / "out",
    )  # fmt: skip
    assert result.returncode == 2
    assert "--well survey_date_last=0" in result.stderr
    assert "'0' is a number, not a date (write it as 2026-03-02)" in result.stderr
    assert "Traceback" not in result.stderr
    assert not (tmp_path / "out" / "trajectory.csv").exists()


def test_a_last_day_override_before_the_file_s_date_names_the_file(tmp_path):
    """``--well survey_date_last=…`` alone, before the survey date the listing states: the
    run's well would be out of order; refused naming the file and its date."""
    listing = tmp_path / "survey.csv"
    listing.write_text("Survey Date: 2026-03-02\nMD[m],INC[deg],AZI TN[deg]\n0,0,0\n100,1,45\n")
    run = ("run", ROOT / "pipelines" / "survey.yaml", "--input", f"stations={listing}")
    refused = gyropipe_cli(*run, "--well", "survey_date_last=2026-03-01", "--out", tmp_path / "a")
    assert refused.returncode != 0 and not (tmp_path / "a").exists()
    assert f"{listing}: the file states survey_date 2026-03-02" in refused.stderr
    assert "survey_date_last 2026-03-01 is before survey_date 2026-03-02" in refused.stderr
    assert "Traceback" not in refused.stderr
    later = ("--well", "survey_date_last=2026-03-04", "--out", tmp_path / "b")
    gyropipe_cli(*run, *later, check=True)
    assert (tmp_path / "b" / "trajectory.csv").exists()
