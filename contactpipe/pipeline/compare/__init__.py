"""The comparison stage: error tables of an archive against a closed form or a reference
archive (:mod:`.tables`), and the closed forms a scene admits (:mod:`.reference`)."""
from .tables import (compare, load_dataset, write_table, format_table, check_table_path,
                     physical_scales, TABLE_SUFFIXES)

__all__ = ["compare", "load_dataset", "write_table", "format_table", "check_table_path",
           "physical_scales", "TABLE_SUFFIXES"]
