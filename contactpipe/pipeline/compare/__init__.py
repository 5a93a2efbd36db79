"""The comparison stage: error tables of an archive against a closed form or a reference
archive (:mod:`.tables`), and the closed forms a scene admits (:mod:`.reference`)."""
from .tables import (
                     TABLE_SUFFIXES,
                     check_table_path,
                     compare,
                     format_table,
                     load_dataset,
                     physical_scales,
                     write_table,
)

__all__ = ["compare", "load_dataset", "write_table", "format_table", "check_table_path",
           "physical_scales", "TABLE_SUFFIXES"]
