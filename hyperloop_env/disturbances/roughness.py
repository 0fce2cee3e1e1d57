"""Roughness: the stochastic guideway irregularity (the first disturbance).

The irregularity is a stationary random profile with the German high-speed "low
irregularity" spectrum (vertical per side and lateral alignment; see
:mod:`hyperloop_env.physics.irregularity`) over 2–200 m wavelengths. Its amplitude is a
continuous factor of a reference spectrum: ``Roughness(severity=s)`` scales the profile by
``s`` (the PSD by ``s²``).

* ``severity`` [-]: amplitude factor relative to the German "low" spectrum
  (``"german-low"``: about 2.5 mm RMS vertical over the band). The maglev-grade default
  of the scenarios is 0.1 (the named class ``"maglev"``), ``"maglev-rough"`` is 0.25.
* ``spectrum``: the reference class (:data:`~hyperloop_env.physics.params.IRREGULARITY_CLASSES`).
  A named class keeps its own amplitude, so ``Roughness.from_class("maglev")`` is the
  default track exactly.

The realisation itself is drawn by the simulator from the episode's seed (spectral
representation); this disturbance acts on the parameters.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import ClassVar

from hyperloop_env.disturbances.base import Disturbance, check_real
from hyperloop_env.physics.params import IRREGULARITY_CLASSES, ModelParams

REFERENCE_SPECTRUM = "german-low"


@dataclass(frozen=True)
class Roughness(Disturbance):
    """Guideway irregularity: ``severity`` × the amplitude of ``spectrum``."""

    name: ClassVar[str] = "roughness"
    severity_unit: ClassVar[str] = "amplitude factor of the reference spectrum [-]"
    description: ClassVar[str] = "stochastic guideway irregularity (vertical and lateral)"
    scales_with_severity: ClassVar[bool] = True
    scaling_note: ClassVar[str] = "the irregularity is the seed's spectral realisation × severity"

    severity: float = 0.1
    spectrum: str = REFERENCE_SPECTRUM

    def __post_init__(self) -> None:
        check_real(self, "severity", lower=0.0, upper=10.0)
        if self.spectrum not in IRREGULARITY_CLASSES:
            raise ValueError(
                f"Roughness.spectrum must be one of {sorted(IRREGULARITY_CLASSES)}, "
                f"got {self.spectrum!r}"
            )

    @classmethod
    def from_class(cls, spectrum: str) -> Roughness:
        """A named irregularity class at its own amplitude (severity 1 of that class)."""
        if not isinstance(spectrum, str) or spectrum not in IRREGULARITY_CLASSES:
            raise ValueError(
                f"irregularity must be one of {sorted(IRREGULARITY_CLASSES)} "
                f"(IrregularityParams.spectrum), got {spectrum!r}"
            )
        return cls(severity=1.0, spectrum=spectrum)

    @property
    def class_name(self) -> str:
        """The named class this equals, if the amplitude is exactly that class's."""
        return self.spectrum if self.severity == 1.0 else f"{self.spectrum}x{self.severity:g}"

    def configure(self, params: ModelParams) -> ModelParams:
        irr = replace(params.irregularity, spectrum=self.spectrum, amplitude=self.severity)
        return params.with_(irregularity=irr)
