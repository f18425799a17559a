"""MPU-6050 register map as data (the registers and bit fields the driver uses).

Source: InvenSense "MPU-6000 and MPU-6050 Register Map and Descriptions", RM-MPU-6000A-00
rev. 4.2 (2013), and "MPU-6000 and MPU-6050 Product Specification", PS-MPU-6000A-00 rev. 3.4.
Section numbers below are those of the register map document.

Each :class:`Register` names its address, its reset value and its bit fields as
``name -> (high_bit, low_bit)``, so the driver and the test model read like the datasheet and a
bit field written to the wrong place (Adafruit's DLPF setter wrote bits 4:3 instead of 2:0) is a
one-line difference that the tests pin.
"""
from dataclasses import dataclass, field

from ...units import MPU6050_TEMP_LSB_PER_C, MPU6050_TEMP_OFFSET_C


@dataclass(frozen=True)
class Register:
    """One 8-bit register: ``address``, ``reset`` value, bit ``fields`` name -> (high, low)."""

    name: str
    address: int
    reset: int = 0x00
    fields: dict = field(default_factory=dict)
    read_only: bool = False

    def get(self, value, field_name):
        """Extract bit field ``field_name`` from a register ``value``."""
        hi, lo = self.fields[field_name]
        return (value >> lo) & ((1 << (hi - lo + 1)) - 1)

    def put(self, value, field_name, field_value):
        """Return ``value`` with bit field ``field_name`` replaced by ``field_value``."""
        hi, lo = self.fields[field_name]
        width_mask = (1 << (hi - lo + 1)) - 1
        if not 0 <= field_value <= width_mask:
            raise ValueError(f"{self.name}.{field_name} (bits {hi}:{lo}) cannot hold {field_value}")
        return (value & ~(width_mask << lo) & 0xFF) | (field_value << lo)

    def mask(self, field_name):
        """The bits of field ``field_name`` set, the others clear (e.g. ``FIFO_OFLOW_INT`` of
        INT_STATUS, bit 4 -> 0x10); ``value & mask`` tests or isolates the field in place."""
        hi, lo = self.fields[field_name]
        return ((1 << (hi - lo + 1)) - 1) << lo

    def __str__(self):
        return f"{self.name} (0x{self.address:02X})"


# section 4.2: sample rate = gyroscope output rate / (1 + SMPLRT_DIV)
SMPLRT_DIV = Register("SMPLRT_DIV", 0x19, fields={"SMPLRT_DIV": (7, 0)})
# section 4.3: EXT_SYNC_SET bits 5:3, DLPF_CFG bits 2:0
CONFIG = Register("CONFIG", 0x1A, fields={"EXT_SYNC_SET": (5, 3), "DLPF_CFG": (2, 0)})
# section 4.4: self-test bits 7:5, FS_SEL bits 4:3
GYRO_CONFIG = Register("GYRO_CONFIG", 0x1B, fields={"XG_ST": (7, 7), "YG_ST": (6, 6), "ZG_ST": (5, 5),
                                                    "FS_SEL": (4, 3)})
# section 4.5: accelerometer self-test bits 7:5, AFS_SEL bits 4:3
ACCEL_CONFIG = Register("ACCEL_CONFIG", 0x1C, fields={"XA_ST": (7, 7), "YA_ST": (6, 6), "ZA_ST": (5, 5),
                                                      "AFS_SEL": (4, 3)})
# section 4.6: which sensor registers are written to the FIFO at each sample
FIFO_EN = Register("FIFO_EN", 0x23, fields={"TEMP_FIFO_EN": (7, 7), "XG_FIFO_EN": (6, 6),
                                            "YG_FIFO_EN": (5, 5), "ZG_FIFO_EN": (4, 4),
                                            "ACCEL_FIFO_EN": (3, 3), "SLV2_FIFO_EN": (2, 2),
                                            "SLV1_FIFO_EN": (1, 1), "SLV0_FIFO_EN": (0, 0)})
INT_PIN_CFG = Register("INT_PIN_CFG", 0x37, fields={"LATCH_INT_EN": (5, 5), "INT_RD_CLEAR": (4, 4)})
# section 4.16 / 4.17: FIFO overflow interrupt enable and status (status bits clear on read)
INT_ENABLE = Register("INT_ENABLE", 0x38, fields={"FIFO_OFLOW_EN": (4, 4), "I2C_MST_INT_EN": (3, 3),
                                                  "DATA_RDY_EN": (0, 0)})
INT_STATUS = Register("INT_STATUS", 0x3A, read_only=True,
                      fields={"FIFO_OFLOW_INT": (4, 4), "I2C_MST_INT": (3, 3), "DATA_RDY_INT": (0, 0)})
# section 4.17-4.19: sensor output registers, big-endian 16-bit two's complement
ACCEL_XOUT_H = Register("ACCEL_XOUT_H", 0x3B, read_only=True)
TEMP_OUT_H = Register("TEMP_OUT_H", 0x41, read_only=True)
GYRO_XOUT_H = Register("GYRO_XOUT_H", 0x43, read_only=True)
SIGNAL_PATH_RESET = Register("SIGNAL_PATH_RESET", 0x68, fields={"GYRO_RESET": (2, 2), "ACCEL_RESET": (1, 1),
                                                                "TEMP_RESET": (0, 0)})
# section 4.29: FIFO_EN bit 6; FIFO_RESET bit 2 (self-clearing)
USER_CTRL = Register("USER_CTRL", 0x6A, fields={"FIFO_EN": (6, 6), "I2C_MST_EN": (5, 5), "I2C_IF_DIS": (4, 4),
                                                "FIFO_RESET": (2, 2), "I2C_MST_RESET": (1, 1),
                                                "SIG_COND_RESET": (0, 0)})
# section 4.30: reset value 0x40 -- the chip starts asleep
PWR_MGMT_1 = Register("PWR_MGMT_1", 0x6B, reset=0x40,
                      fields={"DEVICE_RESET": (7, 7), "SLEEP": (6, 6), "CYCLE": (5, 5), "TEMP_DIS": (3, 3),
                              "CLKSEL": (2, 0)})
PWR_MGMT_2 = Register("PWR_MGMT_2", 0x6C, fields={"LP_WAKE_CTRL": (7, 6), "STBY_XA": (5, 5), "STBY_YA": (4, 4),
                                                  "STBY_ZA": (3, 3), "STBY_XG": (2, 2), "STBY_YG": (1, 1),
                                                  "STBY_ZG": (0, 0)})
# section 4.31-4.33: FIFO byte count (high byte first), FIFO data port
FIFO_COUNT_H = Register("FIFO_COUNT_H", 0x72, read_only=True)
FIFO_COUNT_L = Register("FIFO_COUNT_L", 0x73, read_only=True)
FIFO_R_W = Register("FIFO_R_W", 0x74)
# section 4.32: WHO_AM_I reads 0x68 on an MPU-6050 whatever the AD0 pin says
WHO_AM_I = Register("WHO_AM_I", 0x75, reset=0x68, read_only=True)

REGISTERS = {r.address: r for r in (
    SMPLRT_DIV, CONFIG, GYRO_CONFIG, ACCEL_CONFIG, FIFO_EN, INT_PIN_CFG, INT_ENABLE, INT_STATUS,
    ACCEL_XOUT_H, TEMP_OUT_H, GYRO_XOUT_H, SIGNAL_PATH_RESET, USER_CTRL, PWR_MGMT_1, PWR_MGMT_2,
    FIFO_COUNT_H, FIFO_COUNT_L, FIFO_R_W, WHO_AM_I)}

# PWR_MGMT_1.CLKSEL values (section 4.30): 0 internal 8 MHz oscillator, 1 PLL with X gyro reference
CLKSEL_INTERNAL = 0
CLKSEL_PLL_XGYRO = 1

# GYRO_CONFIG.FS_SEL -> (full scale deg/s, sensitivity LSB per deg/s); product spec section 6.1
GYRO_FULL_SCALE = {0: (250, 131.0), 1: (500, 65.5), 2: (1000, 32.8), 3: (2000, 16.4)}

# ACCEL_CONFIG.AFS_SEL -> (full scale g, sensitivity LSB per g); product spec section 6.2
ACCEL_FULL_SCALE = {0: (2, 16384.0), 1: (4, 8192.0), 2: (8, 4096.0), 3: (16, 2048.0)}
# the accelerometer's output rate (Hz), whatever the sample rate: above it the same accelerometer
# sample is written more than once (register map section 4.2, note)
ACCEL_OUTPUT_RATE_HZ = 1000.0

# CONFIG.DLPF_CFG -> (gyro bandwidth Hz, gyro delay ms, gyroscope output rate Hz); section 4.3
DLPF = {0: (256.0, 0.98, 8000.0), 1: (188.0, 1.9, 1000.0), 2: (98.0, 2.8, 1000.0), 3: (42.0, 4.8, 1000.0),
        4: (20.0, 8.3, 1000.0), 5: (10.0, 13.4, 1000.0), 6: (5.0, 18.6, 1000.0), 7: (None, None, 8000.0)}

# FIFO: 1024 bytes on the MPU-6050 (product spec section 7.17); written in register order
# (accelerometer 0x3B-0x40, temperature 0x41-0x42, gyro 0x43-0x48: register map section 4.6)
FIFO_SIZE_BYTES = 1024

# Temperature (register map section 4.18): T / degC = TEMP_OUT / 340 + 36.53 (their home: gyrofilter.units)
TEMP_LSB_PER_C = MPU6050_TEMP_LSB_PER_C
TEMP_OFFSET_C = MPU6050_TEMP_OFFSET_C
