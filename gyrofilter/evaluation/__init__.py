"""How well the filters do: the evaluation over real recordings, simulated profiles and the
optical reference (``evaluate``; its ``filters``, ``datasets`` and ``metrics``), and reading that
reference (``reference``). Uses the core, ``gyrofilter.filter`` and ``gyrofilter.sim``."""
