// gyrofilter_stream: stream an MPU6050's gyro and accelerometer over serial in gyrofilter's line protocol.
//
// Protocol (docs/live.md): one header line, sent at start-up and whenever a '?' arrives,
//   # gyrofilter-serial: 1 gyro_unit=lsb lsb_per_dps=131 sample_rate_hz=100 ... accel_unit=lsb lsb_per_g=16384 ...
// then one line per sample:  counter,gx,gy,gz,temp,ax,ay,az  (raw int16 LSB; temp raw, T = raw/340 + 36.53 C).
// The counter is the sample index on the sensor's clock: samples lost in a FIFO overflow show as
// a jump, which gyrofilter records as a gap. Lines starting with '#' are messages.
//
// Wiring (Arduino Uno/Nano): MPU6050 VCC-5V (GY-521 board has a regulator), GND-GND,
// SDA-A4, SCL-A5, AD0-GND (address 0x68). Host side:
//   gyrofilter record --source serial:/dev/ttyACM0,baud=115200 --out log.csv.gz
// 115200 baud carries about 250 lines/s of eight fields: for 1 kHz set SAMPLE_RATE_HZ 1000 and BAUD 1000000.
//
// Registers and bit fields: MPU-6000/MPU-6050 Register Map and Descriptions rev 4.2.

#include <Wire.h>

// ----------------------------------------------------------------- settings
#define BAUD 115200
#define MPU_ADDR 0x68          // 0x69 with AD0 high
#define SAMPLE_RATE_HZ 100     // 1000 / (1 + SMPLRT_DIV) with the DLPF on: 4..1000 Hz
#define FS_SEL 0               // 0: +-250, 1: +-500, 2: +-1000, 3: +-2000 deg/s
#define AFS_SEL 0              // 0: +-2, 1: +-4, 2: +-8, 3: +-16 g
#define DLPF_CFG 3             // CONFIG bits 2:0; 3 = 44 Hz gyro bandwidth (1 kHz gyro output rate)

// ----------------------------------------------------------------- registers (rev 4.2)
#define REG_SMPLRT_DIV 0x19
#define REG_CONFIG 0x1A
#define REG_GYRO_CONFIG 0x1B
#define REG_ACCEL_CONFIG 0x1C
#define REG_FIFO_EN 0x23
#define REG_INT_STATUS 0x3A
#define REG_USER_CTRL 0x6A
#define REG_PWR_MGMT_1 0x6B
#define REG_FIFO_COUNT_H 0x72
#define REG_FIFO_R_W 0x74
#define REG_WHO_AM_I 0x75

#define FIFO_EN_TEMP_GYRO_ACCEL 0xF8   // TEMP_FIFO_EN | XG | YG | ZG | ACCEL_FIFO_EN: 14 bytes per frame
#define FRAME_BYTES 14           // in register order (section 4.7): ax, ay, az, temp, gx, gy, gz
#define FIFO_SIZE 1024
#define INT_FIFO_OFLOW 0x10      // INT_STATUS bit 4
#define USER_CTRL_FIFO_EN 0x40
#define USER_CTRL_FIFO_RESET 0x04
#define PWR_DEVICE_RESET 0x80
#define PWR_CLK_PLL_XGYRO 0x01

static const float LSB_PER_DPS[4] = {131.0, 65.5, 32.8, 16.4};
static const int FULL_SCALE_DPS[4] = {250, 500, 1000, 2000};
static const long LSB_PER_G[4] = {16384, 8192, 4096, 2048};   // +-2, 4, 8, 16 g: product spec rev 3.4, section 6.2

static uint32_t counter = 0;        // sample index of the next frame
static uint32_t fifo_started_us = 0;
static bool streaming = false;
static uint8_t chip_id = 0;

// ----------------------------------------------------------------- I2C helpers
static bool writeReg(uint8_t reg, uint8_t value) {
  Wire.beginTransmission(MPU_ADDR);
  Wire.write(reg);
  Wire.write(value);
  return Wire.endTransmission() == 0;
}

static int readRegs(uint8_t reg, uint8_t *buf, uint8_t n) {
  Wire.beginTransmission(MPU_ADDR);
  Wire.write(reg);
  if (Wire.endTransmission(false) != 0) return -1;
  uint8_t got = Wire.requestFrom((uint8_t)MPU_ADDR, n);
  for (uint8_t i = 0; i < got; i++) buf[i] = Wire.read();
  return got;
}

static int readReg(uint8_t reg) {
  uint8_t v;
  return readRegs(reg, &v, 1) == 1 ? v : -1;
}

// write, then read back: the configuration is used only if the chip holds it
static bool setReg(uint8_t reg, uint8_t value) {
  return writeReg(reg, value) && readReg(reg) == value;
}

// ----------------------------------------------------------------- protocol
// The header is one line of at most 256 bytes (the protocol's limit; tests/test_serial_protocol.py
// reads it off these prints): counter_bits is the default 32, the range follows from lsb_per_g.
static void sendHeader() {
  Serial.print(F("# gyrofilter-serial: 1 gyro_unit=lsb lsb_per_dps="));
  Serial.print(LSB_PER_DPS[FS_SEL], 1);
  Serial.print(F(" sample_rate_hz="));
  Serial.print(SAMPLE_RATE_HZ);
  Serial.print(F(" fields=counter,gx,gy,gz,temp,ax,ay,az temp_unit=mpu6050_raw accel_unit=lsb lsb_per_g="));
  Serial.print(LSB_PER_G[AFS_SEL]);
  Serial.print(F(" sensor=MPU6050 chip_id=0x"));
  Serial.print(chip_id, HEX);
  Serial.print(F(" full_scale_dps="));
  Serial.print(FULL_SCALE_DPS[FS_SEL]);
  Serial.print(F(" dlpf_cfg="));
  Serial.print(DLPF_CFG);
  Serial.println(F(" firmware=gyrofilter_stream"));
}

static void fail(const __FlashStringHelper *what) {
  streaming = false;
  Serial.print(F("# error: "));
  Serial.println(what);
}

static void fifoRestart() {
  writeReg(REG_USER_CTRL, USER_CTRL_FIFO_RESET);   // empty the FIFO (frame alignment restarts)
  writeReg(REG_USER_CTRL, USER_CTRL_FIFO_EN);
  fifo_started_us = micros();
}

static bool startSensor() {
  int who = readReg(REG_WHO_AM_I);
  if (who < 0) {
    fail(F("no MPU6050 answers at the I2C address: check SDA-A4, SCL-A5, VCC, GND, AD0"));
    return false;
  }
  chip_id = (uint8_t)who;
  if (who != 0x68) {
    Serial.print(F("# error: WHO_AM_I is 0x"));
    Serial.print(who, HEX);
    Serial.println(F(", expected 0x68 (MPU6050); 0x70 MPU6500, 0x71 MPU9250, 0x72/0x98 clones"));
    streaming = false;
    return false;
  }
  writeReg(REG_PWR_MGMT_1, PWR_DEVICE_RESET);       // reset: all registers to defaults, asleep
  uint32_t t0 = millis();
  while (readReg(REG_PWR_MGMT_1) & PWR_DEVICE_RESET) {  // bit clears when the reset is done
    if (millis() - t0 > 200) { fail(F("reset did not finish within 200 ms")); return false; }
    delay(5);
  }
  delay(100);
  bool ok = setReg(REG_PWR_MGMT_1, PWR_CLK_PLL_XGYRO)  // awake, clock from the X gyro PLL
         && setReg(REG_CONFIG, DLPF_CFG & 0x07)          // DLPF_CFG in bits 2:0
         && setReg(REG_GYRO_CONFIG, (FS_SEL & 0x03) << 3) // FS_SEL in bits 4:3
         && setReg(REG_ACCEL_CONFIG, (AFS_SEL & 0x03) << 3) // AFS_SEL in bits 4:3
         && setReg(REG_SMPLRT_DIV, (uint8_t)(((DLPF_CFG == 0 || DLPF_CFG == 7) ? 8000 : 1000) / SAMPLE_RATE_HZ - 1))
         && setReg(REG_FIFO_EN, FIFO_EN_TEMP_GYRO_ACCEL);
  if (!ok) { fail(F("a configuration register did not read back as written")); return false; }
  delay(50);                                            // gyro start-up
  fifoRestart();
  counter = 0;
  streaming = true;
  return true;
}

// ----------------------------------------------------------------- main
void setup() {
  Serial.begin(BAUD);
  Wire.begin();
  Wire.setClock(400000);
  startSensor();
  sendHeader();
}

void loop() {
  while (Serial.available()) {
    if (Serial.read() == '?') sendHeader();
  }
  if (!streaming) {
    static uint32_t last_try = 0;
    if (millis() - last_try > 1000) { last_try = millis(); if (startSensor()) sendHeader(); }
    return;
  }
  int status = readReg(REG_INT_STATUS);
  if (status >= 0 && (status & INT_FIFO_OFLOW)) {
    // frames were dropped: estimate how many from the clock, restart the FIFO, jump the counter
    uint32_t expected = (uint32_t)((uint64_t)(micros() - fifo_started_us) * SAMPLE_RATE_HZ / 1000000UL);
    Serial.println(F("# FIFO overflow: samples lost (the counter jumps)"));
    fifoRestart();
    counter = expected > counter ? expected : counter + FIFO_SIZE / FRAME_BYTES;
    return;
  }
  uint8_t cnt[2];
  if (readRegs(REG_FIFO_COUNT_H, cnt, 2) != 2) return;
  uint16_t n_bytes = ((uint16_t)cnt[0] << 8) | cnt[1];
  uint16_t frames = n_bytes / FRAME_BYTES;   // whole frames only: alignment is kept
  for (uint16_t f = 0; f < frames; f++) {     // one 14-byte burst per frame (Wire buffer: 32)
    uint8_t b[FRAME_BYTES];
    if (readRegs(REG_FIFO_R_W, b, FRAME_BYTES) != FRAME_BYTES) { fifoRestart(); return; }
    int16_t ax = (int16_t)((b[0] << 8) | b[1]);     // big-endian two's complement
    int16_t ay = (int16_t)((b[2] << 8) | b[3]);
    int16_t az = (int16_t)((b[4] << 8) | b[5]);
    int16_t temp = (int16_t)((b[6] << 8) | b[7]);
    int16_t gx = (int16_t)((b[8] << 8) | b[9]);
    int16_t gy = (int16_t)((b[10] << 8) | b[11]);
    int16_t gz = (int16_t)((b[12] << 8) | b[13]);
    Serial.print(counter++);
    Serial.print(',');
    Serial.print(gx);
    Serial.print(',');
    Serial.print(gy);
    Serial.print(',');
    Serial.print(gz);
    Serial.print(',');
    Serial.print(temp);
    Serial.print(',');
    Serial.print(ax);
    Serial.print(',');
    Serial.print(ay);
    Serial.print(',');
    Serial.println(az);                      // "\r\n": the host accepts both line ends
  }
}
