"""A gyro (and accelerometer) streamed over a serial port: the line protocol (``protocol``: its
bytes to rows, pure), its header's fields (``fields``) and the port (``port``: pyserial)."""
