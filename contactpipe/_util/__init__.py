"""Utilities with no physics: atomic files and locks (:mod:`.files`), signals as
interrupts (:mod:`.interrupts`), and the old import paths' deprecation (:mod:`.moved`)."""
