"""Design: fingertip designs through FEM -> sensing -> estimation, one row of metrics per design; may import every
room of controller.

A design (``FingertipDesign``) is the paper's kind of fingertip - rows x cols hemispheres (bump radius, pitch) on a
base layer (thickness, footprint) of a linear-elastic gel (E, nu), read by a capacitive array (sensor pitch, pad fill
factor). A study (``DesignStudy``) fixes what every design goes through: a rigid plate pressed with the grasp force,
then (1) sheared by force control to the load ratios Q/(mu P) of ``load_ratios`` and (2), on another path from the
same press, twisted about the array centre (angle control, for two or more bumps). The sensor reads the FEM's base
pressure (``controller.sensing.sensor``, ``controller.sensing.capacitive``) and the estimator
(``controller.estimation.estimator``) turns it into shear displacements and rotations. Metrics (``METRICS``, one
column each): translational and rotational estimation errors, the stick-ratio drop near gross slip (the criterion of
the paper's Figs. 3/4), force and torque capacity per unit grasp force, and the mesh's error estimate.

``design_sweep`` runs many designs on dask.distributed (a LocalCluster by default, or a scheduler address) or in
this process, resumable: with ``out_dir`` each design's record is written as it finishes and a re-run skips the
designs recorded there (``fem.task_runner``). Designs that differ only in their sensor share one FEM solve (one
task); designs of one geometry share its cached mesh, and a re-run reads the compliance columns from their disk cache.
With ``DesignStudy(closed_loop=True)`` each design is also judged by its grasp (``_grasp``): calibrated on its own
FEM (``contact.reduced.design_fit``, shared by the designs of one mechanical design), its plant and its estimator's
bench built, Table I trials run; the closed-loop columns (``GRASP_METRICS``, ``FIT_METRICS``) join the row.
``python -m studies design DESIGN.toml`` is the command (file format: ``controller.design._file``).
"""

from ._evaluate import evaluate_designs
from ._file import DesignSweepSpec, load_design_file
from ._grasp import FIT_METRICS, GRASP_METRICS, array_design, grasp_refusal, wilson_interval
from ._metrics import METRICS
from ._spec import DesignStudy, FingertipDesign, SensorModel, design_id, design_scenes, twist_angles
from ._sweep import design_sweep
from ._table import CLOSED_LOOP_COLUMNS, DESIGN_COLUMNS, design_table, increment_table, pareto_front

__all__ = ["FingertipDesign", "DesignStudy", "SensorModel", "METRICS", "design_scenes", "twist_angles",
           "evaluate_designs", "design_sweep", "design_table", "increment_table", "pareto_front", "design_id",
           "load_design_file", "DesignSweepSpec", "DESIGN_COLUMNS", "GRASP_METRICS", "FIT_METRICS",
           "CLOSED_LOOP_COLUMNS", "grasp_refusal", "array_design", "wilson_interval"]
