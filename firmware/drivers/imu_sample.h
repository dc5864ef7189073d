/* One sample of a 6-axis IMU in SI units, as a chip driver hands it to the node.
 *
 * Frame: the sensor frame printed on the chip (right-handed x, y, z). Signs:
 *   - gyr_rads: angular rate about each axis, positive counter-clockwise when looking
 *     from the positive end of the axis towards the origin (right-hand rule);
 *   - acc_mps2: specific force (accelerometer reading, gravity included): a chip lying
 *     still with its z axis pointing up reads about +9.81 m/s^2 on z.
 */
#ifndef FIRMWARE_DRIVERS_IMU_SAMPLE_H
#define FIRMWARE_DRIVERS_IMU_SAMPLE_H

#include <stdbool.h>

typedef struct {
  float gyr_rads[3]; /* angular rate, rad/s, sensor frame */
  float acc_mps2[3]; /* specific force, m/s^2, sensor frame, gravity included */
  float temp_degc;   /* die temperature, deg C */
  bool acc_clipped;  /* some accelerometer axis at full scale (saturated) */
  bool gyr_clipped;  /* some gyroscope axis at full scale (saturated) */
} imu_sample_t;

#endif /* FIRMWARE_DRIVERS_IMU_SAMPLE_H */
