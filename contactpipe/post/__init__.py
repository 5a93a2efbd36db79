"""Post-processing of an archive: subsurface stresses (:mod:`.stress`), multiaxial
fatigue criteria over them (:mod:`.fatigue`) and the fretting regime of a loop
(:mod:`.fretting`). Nothing is imported until a module is asked for."""
