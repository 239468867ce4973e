"""A fingertip design's nominal plant: its FEM-calibrated bump laws and its per-bump FEM base response, as one value.

``nominal_model()`` is the shipped 3x3 fingertip (the packaged calibration and base-response files of
``contact.reduced``); ``PlantModel.from_fit`` is any design calibrated from its own FEM
(``contact.reduced.design_fit.fit_fingertip``). A ``FingertipPlant`` builds both fingertips of a trial from one model
and the build's factors. Models are known by their ``key`` (the fit's cache key, or the packaged files' digest):
two models with one key are one model, so the plant's pad-force tables are cached per key.
"""

from __future__ import annotations

import functools
import hashlib
from dataclasses import dataclass
from pathlib import Path

__all__ = ["PlantModel", "nominal_model"]


@dataclass(frozen=True, eq=False)
class PlantModel:
    """mechanics : ReducedFingertip -- the design's calibrated bump laws; response : BaseResponse -- each bump's
    base-pressure field from the design's FEM; key : str -- identity (equal keys, equal models)."""

    mechanics: object
    response: object
    key: str

    def __post_init__(self):
        from contact.reduced import ReducedFingertip
        from contact.reduced.base_response import BaseResponse

        if not isinstance(self.mechanics, ReducedFingertip):
            raise ValueError(f"mechanics={self.mechanics!r} must be a ReducedFingertip")
        if not isinstance(self.response, BaseResponse):
            raise ValueError(f"response={self.response!r} must be a BaseResponse")
        if self.response.design != self.mechanics.design:
            raise ValueError(f"the base response is of design {self.response.design}, the bump laws of "
                             f"{self.mechanics.design}: a plant needs both of one design")
        if not isinstance(self.key, str) or not self.key:
            raise ValueError(f"key={self.key!r} must be a non-empty string")

    def __hash__(self) -> int:
        return hash(self.key)

    def __eq__(self, other) -> bool:
        return isinstance(other, PlantModel) and other.key == self.key

    @property
    def design(self):
        """The ArrayFingertipDesign of the model."""
        return self.mechanics.design

    @classmethod
    def from_files(cls, calibration, response) -> "PlantModel":
        """From a calibration JSON (``contact.reduced.save_calibration``) and a base-response file
        (``BaseResponse.save``); the key is the digest of both files' bytes."""
        from contact.reduced import ReducedFingertip
        from contact.reduced.base_response import BaseResponse

        digest = hashlib.sha256()
        for path in (calibration, response):
            digest.update(Path(path).read_bytes())
        return cls(ReducedFingertip.calibrated(calibration), BaseResponse.load(response), f"files-{digest.hexdigest()}")

    @classmethod
    def from_fit(cls, fitted) -> "PlantModel":
        """From a design calibrated on its own FEM (``contact.reduced.design_fit.FittedFingertip``)."""
        return cls(fitted.mechanics, fitted.response, f"fit-{fitted.key}")


@functools.lru_cache(maxsize=1)
def nominal_model() -> PlantModel:
    """The shipped 3x3 fingertip: the packaged calibration and base response of ``contact.reduced``."""
    from contact.reduced import PACKAGED_CALIBRATION
    from contact.reduced.base_response import PACKAGED_BASE_RESPONSE

    return PlantModel.from_files(PACKAGED_CALIBRATION, PACKAGED_BASE_RESPONSE)
