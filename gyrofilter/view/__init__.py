"""Watching a run from outside the process: the live view in a browser (``gyrofilter run --serve``)
and the UDP streams to PlotJuggler or Teleplot (``gyrofilter run --udp``); and the sensor report,
one HTML file to read in a browser (``gyrofilter report``).

A wing of layer 3, beside ``sources/`` and ``analysis/``: it imports the core and ``analysis/``, and nothing
imports it but the commands (``import gyrofilter`` never loads a server). One module per idea:

- :mod:`~gyrofilter.view.sink`: what the run loop hands over (:class:`~gyrofilter.view.sink.RunInfo`
  once, a :class:`~gyrofilter.view.sink.Step` per read) and the three calls every outlet has:
  ``start(info)``, ``feed(step)`` (never waits for the network), ``close()`` (a summary);
- :mod:`~gyrofilter.view.address`: ``[HOST:]PORT`` as the options take it, checked and resolved;
- :mod:`~gyrofilter.view.still_allan`: the Allan deviation of the still stretches so far, in
  bounded memory;
- :mod:`~gyrofilter.view.state`: what the view shows, fed by the run loop, read by the server;
- :mod:`~gyrofilter.view.server`: the HTTP server (``/``, ``/stream``, ``/status``), read-only;
- :mod:`~gyrofilter.view.udp`: one datagram per filtered row;
- ``page/``: the page, its script and its style sheet (package data; nothing from elsewhere);
- :mod:`~gyrofilter.view.report`: the sensor report's page, drawn from its data (the allan and gap
  documents, replay's summary) with :mod:`~gyrofilter.view.svg`, figures as inline SVG text.
"""
