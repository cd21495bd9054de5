// torque_model_torque / torque_model_rate: E and dE/dt of flatstep.model.torque_model, terms skipped when zero.
#include "torque_model.h"
#include "plan.h"

// Returns true when x is finite and >= 0.
static bool nonnegative(fs_real x)
{
    return fs_isfinite(x) && x >= 0;
}

// Returns true when every field is finite and in range.
bool torque_model_valid(const struct torque_model *m)
{
    return nonnegative(m->detent_torque) && (m->detent_torque == 0 || m->detent_harmonic >= 1)
           && fs_isfinite(m->detent_phase) && nonnegative(m->coulomb_torque)
           && (m->coulomb_torque == 0 || (fs_isfinite(m->coulomb_speed) && m->coulomb_speed > 0))
           && fs_isfinite(m->load) && fs_isfinite(m->load_step) && fs_isfinite(m->load_t0) && fs_isfinite(m->load_tf)
           && (m->load_step == 0 || m->load_tf > m->load_t0);
}

// Returns true when E is the constant load alone: every term but m->load is skipped (torque_model.h).
bool torque_model_constant(const struct torque_model *m)
{
    return m->load_step == 0 && !(m->detent_torque > 0) && !(m->coulomb_torque > 0);
}

// Returns E [N m] at time t, angle theta and speed omega for a motor of Nr rotor teeth.
fs_real torque_model_torque(const struct torque_model *m, int Nr, fs_real t, fs_real theta, fs_real omega)
{
    fs_real out = m->load, s, c;
    if (m->load_step != 0)
        out = out + m->load_step * plan_psi(t, m->load_t0, m->load_tf, 0);
    if (m->detent_torque > 0) {
        fs_sincos((fs_real)(m->detent_harmonic * (uint32_t)Nr) * theta + m->detent_phase, &s, &c);
        out = out + m->detent_torque * s;
    }
    if (m->coulomb_torque > 0)
        out = out + m->coulomb_torque * fs_tanh(omega / m->coulomb_speed);
    return out;
}

// Returns dE/dt [N m/s] along a motion with angle theta, speed omega and acceleration acc at time t.
fs_real torque_model_rate(const struct torque_model *m, int Nr, fs_real t, fs_real theta, fs_real omega, fs_real acc)
{
    fs_real out = 0, s, c, th, hNr = (fs_real)(m->detent_harmonic * (uint32_t)Nr);
    if (m->load_step != 0)
        out = m->load_step * plan_psi(t, m->load_t0, m->load_tf, 1);
    if (m->detent_torque > 0) {
        fs_sincos(hNr * theta + m->detent_phase, &s, &c);
        out = out + m->detent_torque * hNr * c * omega;
    }
    if (m->coulomb_torque > 0) {
        th = fs_tanh(omega / m->coulomb_speed);
        out = out + m->coulomb_torque / m->coulomb_speed * (1 - th * th) * acc;
    }
    return out;
}
