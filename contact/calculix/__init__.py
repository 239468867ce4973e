"""An independent finite-strain reference: CalculiX (``ccx``, from a package registry) run on the project's problems.

Decks are written from Python as plain text (``_deck``), on gmsh meshes in CalculiX's node order (``_mesh``); the
printed tables (``.dat``) and nodal results (``.frd``) are parsed back (``_files``). Two problems: a rigid sphere
pressed into a bonded layer (axisymmetric, frictionless) and one bump of the paper's fingertip pressed, then sheared
or twisted by a rigid plate with Coulomb friction (3D, mortar contact). The gel is linear elastic without NLGEOM
(the project's small-strain law) or a compressible Neo-Hookean solid with NLGEOM (``GelLaw``). The same problems as
scenes of the project's linear solver are in ``_scenes``. Runs are kept on disk by the deck's hash
(``<FINGERTIP_CACHE>/calculix``); without ccx, ``CalculixUnavailable`` (an OSError) says how to install it.
"""

from contact.calculix._cases import (SLIP_TOLERANCE, BumpRecord, BumpSetup, CalculixJob, PressRecord, SpherePress,
                                     bump_job, bump_path, bump_press_job, contact_state,
                                     sphere_press, sphere_press_job)
from contact.calculix._deck import GelLaw
from contact.calculix._files import DatTable, FrdStep, read_dat, read_frd
from contact.calculix._run import (INSTALL_HINT, CalculixFailed, CalculixUnavailable, ccx_executable, ccx_version,
                                   run_deck)
from contact.calculix._scenes import bump_scene, sphere_press_scene

__all__ = ["GelLaw", "SpherePress", "PressRecord", "BumpSetup", "BumpRecord", "CalculixJob", "sphere_press_job",
           "sphere_press", "bump_job", "bump_path", "bump_press_job", "SLIP_TOLERANCE", "contact_state",
           "sphere_press_scene", "bump_scene",
           "CalculixUnavailable", "CalculixFailed", "ccx_executable", "ccx_version", "run_deck", "INSTALL_HINT",
           "DatTable", "FrdStep", "read_dat", "read_frd"]
