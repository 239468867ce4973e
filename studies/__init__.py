"""One module per figure, table or study; ``python -m studies NAME --out DIR`` runs one (see ``--help``)."""

from studies._output import save_figure, write_csv_atomic, write_json_atomic
from studies._registry import find_studies

__all__ = ["find_studies", "save_figure", "write_csv_atomic", "write_json_atomic"]
