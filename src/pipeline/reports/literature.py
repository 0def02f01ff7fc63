"""Published works a report cites for its methods, as reference-list entries, and the
numbering of the citations in one report (in order of first citation)."""

from __future__ import annotations

from pipeline.reports.document import Fields

DRIFT_CALIBRATION = (
    "Usovershenstvovannaya metodika opredeleniya kursovogo ukhoda giroskopicheskikh "
    "inklinometrov [An improved method of determining the azimuth drift of gyroscopic "
    "inclinometers]. In Russian; author not stated."
)
"""Drift rate of a free gyro from the series of its azimuth calibration."""
MULTI_POSITION = (
    "Binder Ya. I., Khazov I. A. Versatile gyroinclinometer based on a single axis angular "
    "rate sensor [Universal'nyi giroskopicheskii inklinometr na baze edinstvennogo "
    "odnoosnogo datchika uglovoi skorosti]. Journal of the Russian Universities. "
    "Radioelectronics, 2023, vol. 26, no. 4, pp. 133–148. "
    "doi:10.32603/1993-8985-2023-26-4-133-148. In Russian."
)
"""Multi-position gyrocompassing with a gyro on a rotating frame."""
DATA_VALIDITY = (
    "Rozrobka metodiv otsinky dostovirnosti danykh v inklinometrychnykh prystroiakh, "
    "pobudovanykh na datchykakh kutovoi shvydkosti, mahnitometrakh ta akselerometrakh "
    "[Development of methods for assessing the validity of data in inclinometers built on "
    "angular rate sensors, magnetometers and accelerometers]. In Ukrainian; author not "
    "stated."
)
"""Validity of sensor data against the Earth's rotation, gravity and magnetic field."""
ERROR_MODEL = (
    "Williamson H. S. Accuracy prediction for directional measurement while drilling. "
    "SPE Drilling & Completion, 2000, vol. 15, no. 4, pp. 221–233 (SPE 67616)."
)
"""Propagation of survey tool errors into position uncertainty (the ISCWSA model)."""
GYRO_ERROR_MODEL = (
    "Torkildsen T., Håvardstein S. T., Weston J. L., Ekseth R. Prediction of wellbore position "
    "accuracy when surveyed with gyroscopic tools. SPE Annual Technical Conference and "
    "Exhibition, Houston, 26–29 September 2004 (SPE 90408)."
)
"""The ISCWSA error model of gyroscopic survey tools."""
SEPARATION_RULE = (
    "Sawaryn S. J., Wilson H., Bang J., Nyrnes E., Sentance A., Poedjono B., Lowdon R., "
    "Mitchell I., Codling J., Clark P. J., Allen W. T. Well-collision-avoidance separation "
    "rule. SPE Drilling & Completion, 2019, vol. 34, no. 1, pp. 1–15 (SPE-187073-PA)."
)
"""The ISCWSA separation factor between a reference and an offset well."""


class Citations:
    """The works cited in one report, numbered in order of first citation."""

    def __init__(self) -> None:
        self.works: list[str] = []

    def cite(self, work: str) -> str:
        """The citation mark of ``work`` ('[1]'), numbering it on first use."""
        if work not in self.works:
            self.works.append(work)
        return f"[{self.works.index(work) + 1}]"

    def fields(self) -> Fields | None:
        """The reference list (None: nothing cited)."""
        if not self.works:
            return None
        return Fields("References", tuple((f"[{k}]", work) for k, work in enumerate(self.works, 1)))
