"""The MPU6050 over I2C (smbus2): ``driver`` opens and reads the chip's FIFO
(:func:`~gyrofilter.sources.mpu6050.driver.open_mpu6050`), ``chip`` computes its settings and
decodes its frames without the bus, ``registers`` is the register map, and ``model`` a
register-level model of the chip that the tests and benchmarks put behind smbus2's ``ioctl``."""
