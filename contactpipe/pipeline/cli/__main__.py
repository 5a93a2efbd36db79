"""``python -m contactpipe.pipeline.cli``: the ``contactpipe`` command."""
import sys

from .main import main

sys.exit(main())
