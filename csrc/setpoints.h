// Replay of a setpoint stream: a table of setpoints sampled at a fixed rate (flatstep.plan.export), as a
// field-oriented drive that takes feedforward terms reads it, one row per control period or interpolated.
#ifndef FS_SETPOINTS_H
#define FS_SETPOINTS_H

#include <stdint.h>
#include "fs_real.h"

// cffi:begin

// The columns of a row, in the order flatstep.plan.export.SETPOINT_COLUMNS writes them.
enum setpoint_column {
    SETPOINT_THETA = 0,   // rotor angle [rad]
    SETPOINT_OMEGA = 1,   // speed [rad/s]
    SETPOINT_ALPHA = 2,   // acceleration [rad/s^2]
    SETPOINT_TORQUE = 3,  // torque the move needs: J alpha + B omega + load [N m]
    SETPOINT_ID = 4,      // d current [A]
    SETPOINT_IQ = 5,      // q current [A]
    SETPOINT_LEN = 6
};

// How setpoint_at reads between rows.
enum setpoint_mode {
    SETPOINT_HOLD = 0,   // the row at or before t (zero-order hold)
    SETPOINT_LINEAR = 1  // linear between the rows around t
};

enum setpoint_status { SETPOINT_OK = 0, SETPOINT_EARGS = 1 };

// A stream in caller-owned memory (a const table in flash): row k, at t0 + k / rate, is
// rows[k * SETPOINT_LEN .. k * SETPOINT_LEN + SETPOINT_LEN - 1].
struct setpoint_stream {
    const float *rows;  // n x SETPOINT_LEN floats, row-major
    uint32_t n;         // number of rows, >= 1
    double t0;          // time of row 0 [s]
    double rate;        // rows per second [Hz], > 0
};

// Writes the setpoints at time t to out (SETPOINT_LEN values): before t0 row 0, after the last row the last row,
// between rows as mode says. Returns SETPOINT_EARGS (and writes nothing) for a null pointer, n = 0, a rate that
// is not finite and positive, a t0 or t that is not finite, or an unknown mode.
int setpoint_at(const struct setpoint_stream *s, double t, int mode, fs_real out[SETPOINT_LEN]);

// cffi:end

#endif
