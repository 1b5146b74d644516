"""The water: the current (:mod:`~jaxnet.water.current`), the waves (:mod:`~jaxnet.water.waves`) and their
spectra (:mod:`~jaxnet.water.spectra`), and the loads that vary in time (:mod:`~jaxnet.water.forcing`).
"""
