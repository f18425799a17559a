"""How well the filters do: the evaluation over real recordings, simulated profiles and the
optical reference (``evaluate``), and reading that reference (``reference``). Uses the core and
``gyrofilter.sim``."""
