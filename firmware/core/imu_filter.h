/* The node's orientation filter: gyroscope strapdown integration corrected by the
 * accelerometer (inclination) and, in 9D, by the magnetometer (heading), with gyroscope
 * bias estimation at rest and during motion and magnetic disturbance rejection.
 *
 * Frames: S the sensor; I a quasi-inertial frame, the strapdown integral of the gyroscope;
 * E6 an earth frame with z up and an arbitrary heading (the 6D result); E the ENU earth
 * frame (x east, y magnetic north, z up).
 *   q(S->E) = heading(E6->E) ⊗ inclination(I->E6) ⊗ strapdown(S->I)
 * The accelerometer is low-pass filtered in I, where linear accelerations average out, and
 * the inclination quaternion keeps that filtered vector vertical. The horizontal
 * inclination corrections measure the gyroscope bias during motion (a Kalman filter, its
 * measurement matched to the same low-pass); at rest the low-passed gyroscope measures it
 * directly. The heading is corrected toward magnetic north while the field's norm and dip
 * match a learned reference. Method and figures: docs/firmware.md.
 *
 * Float32 only, no allocation, all state in imu_filter_t. One update per IMU sample.
 */
#ifndef FIRMWARE_CORE_IMU_FILTER_H
#define FIRMWARE_CORE_IMU_FILTER_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

typedef struct {
  float acc_time_constant_s;         /* s, mean delay of the accelerometer low-pass in I */
  float acc_damping;                 /* 1, its damping ratio (0.707 Butterworth, 1 critical) */
  float mag_time_constant_s;         /* s, heading correction time constant */
  float rest_time_s;                 /* s, stillness needed before "at rest" */
  float rest_filter_time_constant_s; /* s, low-pass of the rest detection */
  float rest_gyr_threshold_rads;     /* rad/s, gyroscope deviation from its low-pass */
  float rest_acc_threshold_mps2;     /* m/s^2, accelerometer deviation from its low-pass */
  float bias_limit_rads;             /* rad/s, largest bias estimate (and measurement error) */
  float bias_sigma_init_rads;        /* rad/s, uncertainty of the bias at start */
  float bias_sigma_motion_rads;      /* rad/s, steady uncertainty reached during motion */
  float bias_sigma_rest_rads;        /* rad/s, steady uncertainty reached at rest */
  float bias_forgetting_time_s;      /* s, the bias uncertainty grows by 0.1 deg/s in this time */
  float bias_vertical_forgetting;    /* 1, weight of "no bias about the vertical" vs motion */
  float bias_update_rate_hz;         /* Hz, the bias estimator runs at about this rate */
  float mag_current_time_constant_s; /* s, low-pass of the field's norm and dip */
  float mag_ref_time_constant_s;     /* s, adaptation of the reference norm and dip */
  float mag_norm_threshold;          /* 1, relative norm deviation that means "disturbed" */
  float mag_dip_threshold_rad;       /* rad, dip deviation that means "disturbed" */
  float mag_new_time_s;              /* s, a steady new field replaces the reference after */
  float mag_new_first_time_s;        /* s, the same for the first reference */
  float mag_new_min_gyr_rads;        /* rad/s, ... counting only while turning this fast */
  float mag_min_undisturbed_time_s;  /* s, undisturbed this long before correcting again */
  float mag_max_rejection_time_s;    /* s, longest heading hold; then corrections resume */
  float mag_rejection_factor;        /* 1, gain divisor after the hold; hold time recovery rate */
  bool motion_bias_enabled;          /* estimate the bias during motion */
  bool rest_bias_enabled;            /* estimate the bias at rest */
  bool mag_rejection_enabled;        /* detect and reject magnetic disturbances */
} imu_filter_settings_t;

extern const imu_filter_settings_t imu_filter_settings_default;

/* A second-order low-pass y'' = w^2 (x - y) - 2 zeta w y' in state-variable form (output
 * y and scaled rate u = y'/w, robust in float32 for cut-offs far below the rate), its mean
 * delay 2 zeta / w the settings' time constant. It starts as a running mean until it has
 * seen one time constant of data. */
typedef struct {
  float gain;             /* 1, w times the step period (0: pass through) */
  float damping2;         /* 1, 2 zeta */
  uint32_t steps;         /* steps averaged so far, 0 once filtering */
  uint32_t average_steps; /* steps to average before filtering */
} imu_filter_lowpass_t;

/* Coefficients computed once by imu_filter_init. */
typedef struct {
  bool valid;                /* settings were usable */
  float sample_period_s;     /* s */
  uint32_t bias_decimation;  /* samples per bias estimator step */
  float bias_period_s;       /* s, bias_decimation * sample_period_s */
  float bias_p0;             /* (rad/s)^2, largest bias variance */
  float bias_v;              /* (rad/s)^2, variance growth per bias step */
  float bias_w_motion;       /* (rad/s)^2, horizontal measurement variance in motion */
  float bias_w_vertical;     /* (rad/s)^2, variance of "no vertical bias" */
  float bias_w_rest;         /* (rad/s)^2, measurement variance at rest */
  float rest_gyr_threshold2; /* (rad/s)^2 */
  float rest_acc_threshold2; /* (m/s^2)^2 */
  float mag_gain;            /* 1, heading correction per sample */
  float mag_ref_gain;        /* 1, reference adaptation per sample */
  float mag_current_gain;    /* 1, norm/dip low-pass per sample */
} imu_filter_coefficients_t;

typedef struct {
  float norm_dip_lp1[2];       /* uT, rad: first stage of the norm and dip low-pass */
  float norm_dip[2];           /* uT, rad: low-passed norm and dip of the field */
  uint32_t samples;            /* magnetometer samples used */
  float ref_norm_ut;           /* uT, reference norm (0: none learned yet) */
  float ref_dip_rad;           /* rad, reference dip (down positive) */
  float candidate_norm_ut;     /* uT, a new steady field being watched (-1: none) */
  float candidate_dip_rad;     /* rad */
  float candidate_time_s;      /* s, turning time the candidate has been steady */
  float undisturbed_time_s;    /* s, time the field matched the reference */
  float rejection_time_s;      /* s, heading hold time used up (recovers when clean) */
  float init_gain;             /* 1, gain floor of the initial heading average (0: done) */
  float time_s;                /* s, magnetometer data seen (for settled), saturates */
  uint16_t steps_since_sample; /* updates since the last magnetometer sample */
  bool disturbed;              /* the field differs from the reference */
  bool heading_held;           /* the last sample made no heading correction */
} imu_filter_mag_t;

typedef struct {
  float gyr_lp[3], gyr_lp_rate[3]; /* rad/s, low-pass of the gyroscope, its rate */
  float acc_lp[3], acc_lp_rate[3]; /* m/s^2, low-pass of the accelerometer, its rate */
  imu_filter_lowpass_t gyr_filter, acc_filter;
  float still_time_s; /* s, time both deviations stayed under the thresholds */
  bool gyr_still;     /* the last gyroscope sample was still */
  bool at_rest;       /* still for rest_time_s */
} imu_filter_rest_t;

typedef struct {
  float bias_rads[3];            /* rad/s, estimate, sensor frame */
  float p[6];                    /* (rad/s)^2, covariance: xx, xy, xz, yy, yz, zz */
  float r_lp[11], r_lp_rate[11]; /* low-pass of R(S->E6) row-major (1), then of
                                    (R bias) x and y (rad/s); its rate */
  imu_filter_lowpass_t r_filter;
  float correction_sum[2]; /* 1, E6 x and y of the normalised filtered acc since last step */
  uint32_t phase;          /* samples since the last bias step */
} imu_filter_bias_t;

/* All state, caller-owned: no pointers inside, so a copy is a snapshot. */
typedef struct {
  imu_filter_settings_t settings;
  imu_filter_coefficients_t coeff;
  float gyr_quat[4];               /* 1, S -> I, strapdown */
  float acc_quat[4];               /* 1, I -> E6, inclination correction */
  float heading_rad;               /* rad, E6 -> E about up, in (-pi, pi] */
  float acc_lp[3], acc_lp_rate[3]; /* m/s^2, accelerometer low-passed in I, its rate */
  imu_filter_lowpass_t acc_filter;
  float acc_time_s; /* s, accelerometer data seen (for settled), saturates */
  imu_filter_rest_t rest;
  imu_filter_bias_t bias;
  imu_filter_mag_t mag;
  uint32_t gyr_rejected; /* gyroscope vectors skipped (bad input) */
  uint32_t acc_rejected; /* accelerometer vectors skipped */
  uint32_t mag_rejected; /* magnetometer vectors skipped */
} imu_filter_t;

/* True when `settings` and `sample_period_s` can run (positive, finite periods and gains). */
bool imu_filter_settings_valid(const imu_filter_settings_t *const settings, float sample_period_s);

/* Sets up the filter; invalid settings leave it refusing every sample (counted). */
void imu_filter_init(imu_filter_t *const filter, const imu_filter_settings_t *const settings,
                     float sample_period_s);

/* One sample at the init's period. gyr rad/s, acc m/s^2 (gravity included), sensor frame.
 * mag_ut: magnetometer in uT, sensor frame, or NULL (no heading correction this sample; a
 * magnetometer slower than the IMU passes NULL between its readings). A vector that is not
 * finite or absurdly large is skipped and counted (imu_filter_rejected). */
void imu_filter_update(imu_filter_t *const filter, const float gyr_rads[3], const float acc_mps2[3],
                       const float *const mag_ut);

/* Orientation, sensor -> ENU earth (9D; in 6D the heading is the gyroscope's). */
void imu_filter_quaternion(const imu_filter_t *const filter, float q_wxyz[4]);

/* Orientation sensor -> E6: inclination only, heading free (no magnetometer used). */
void imu_filter_quaternion_6d(const imu_filter_t *const filter, float q_wxyz[4]);

/* 9D: the last magnetometer sample left the heading on the gyroscope (disturbed field). */
bool imu_filter_mag_disturbed(const imu_filter_t *const filter);

/* Initial alignment done (inclination averaged, and the heading too once a magnetometer
 * sample came): the output can be trusted. */
bool imu_filter_settled(const imu_filter_t *const filter);

/* The sensor has been still for the settings' rest time. */
bool imu_filter_at_rest(const imu_filter_t *const filter);

/* Gyroscope bias estimate, rad/s, sensor frame. */
void imu_filter_gyro_bias(const imu_filter_t *const filter, float bias_rads[3]);

/* Vectors skipped as bad input since init (gyroscope + accelerometer + magnetometer). */
uint32_t imu_filter_rejected(const imu_filter_t *const filter);

#endif /* FIRMWARE_CORE_IMU_FILTER_H */
