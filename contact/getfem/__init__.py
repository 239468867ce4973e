"""A second independent finite-strain reference: GetFEM (Debian's python3-getfem) on the bump's shear and twist.

CalculiX's Neo-Hookean bump diverges when friction comes on, so the shear and twist of the finite-strain gel have no
CalculiX reference. GetFEM solves them on the project's own tet mesh of the scene (the same P1 space: what differs
is the solver - its hyperelastic law, its large-sliding contact with the plate as a signed-distance obstacle, its
augmented Lagrangian and Newton), in the system interpreter that has GetFEM (``_script.py``; the project never
imports getfem). Runs are kept on disk by the job's hash (``<FINGERTIP_CACHE>/getfem``); without GetFEM,
``GetfemUnavailable`` (an OSError) says how to install it.
"""

from contact.getfem._run import (
                                 INSTALL_HINT,
                                 GetfemFailed,
                                 GetfemJob,
                                 GetfemUnavailable,
                                 bump_job,
                                 getfem_python,
                                 getfem_version,
)

__all__ = ["bump_job", "GetfemJob", "getfem_python", "getfem_version", "GetfemUnavailable", "GetfemFailed",
           "INSTALL_HINT"]
