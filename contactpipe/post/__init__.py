"""Post-processing of an archive: subsurface stresses (:mod:`.stress`), multiaxial
fatigue criteria over them (:mod:`.fatigue`), the fretting regime of a loop
(:mod:`.fretting`) and the stick and slip clusters of a rough contact (:mod:`.clusters`).
Nothing is imported until a module is asked for."""
