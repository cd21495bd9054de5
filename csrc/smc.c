// smc_init / smc_reset / smc_step: the law of flatstep.control.smc, guarded so no input yields NaN or a division by 0.
#include "smc.h"
#include <stddef.h>
#include "flat.h"

// Where ia^2 + ib^2 neither underflows nor overflows, so that sqrt(ia^2 + ib^2) is as good as hypot(ia, ib).
#define RHO2_SAFE_MIN FS_C(1e-30)
#define RHO2_SAFE_MAX FS_C(1e30)

// The step's body is specialised into smc_step (no intermediate values) and smc_step_terms: inline it in both,
// so that smc_step compiles to what it was before smc_step_terms existed.
#if defined(__GNUC__)
#define SMC_INLINE static inline __attribute__((always_inline))
#else
#define SMC_INLINE static inline
#endif

// Returns nothing; fills p with the paper's motor, move (Section 3) and gains, ideal measurement,
// v_limit = 1e3 V, rho_min = 1e-6 A, no torque model and no table.
void smc_params_default(struct smc_params *p)
{
    struct motor_params m = {FS_C(8.4), FS_C(0.010), FS_C(0.05), FS_C(3.6e-6), FS_C(1e-4), 50};
    struct plan pl = {0, FS_C(0.02), FS_C(0.4), FS_C(0.4), FS_C(0.02), FS_C(0.04), NULL};
    struct smc_gains g = {100, 100, FS_C(0.005), FS_C(0.005), FS_C(0.8), 10, 0};
    struct torque_model none = {0, 4, 0, 0, FS_C(0.01), 0, 0, 0, 1};
    struct smc_loss_aware plan_rho = {0, 0};
    p->torques = none;
    p->loss_aware = plan_rho;
    p->motor = m;
    p->plan = pl;
    p->gains = g;
    p->measurement = SMC_IDEAL;
    p->v_limit = FS_C(1e3);
    p->rho_min = FS_C(1e-6);
}

// Returns true when x is finite and > 0.
static bool positive(fs_real x)
{
    return fs_isfinite(x) && x > 0;
}

// Returns SMC_PARAMS_OK, or the smc_param_error naming the invalid group (s is then left unusable).
int smc_init(struct smc *s, const struct smc_params *p)
{
    const struct smc_gains *g = &p->gains;
    if (!motor_params_valid(&p->motor))
        return SMC_EMOTOR;
    if (!plan_valid(&p->plan))
        return SMC_EPLAN;
    if (!(positive(g->W1) && positive(g->W2) && positive(g->eps1) && positive(g->eps2) && positive(g->xi)
          && positive(g->wn)))
        return SMC_EGAINS;
    if (!(fs_isfinite(g->hold_damping) && g->hold_damping >= 0))
        return SMC_EGAINS;
    if (p->measurement != SMC_IDEAL && p->measurement != SMC_MODEL)
        return SMC_EMEASUREMENT;
    if (!positive(p->v_limit) || p->v_limit < FS_C(1e-3) || !positive(p->rho_min))
        return SMC_ELIMITS;
    if (!torque_model_valid(&p->torques))
        return SMC_ETORQUES;
    if (!(fs_isfinite(p->loss_aware.rho_hold) && p->loss_aware.rho_hold >= 0 && fs_isfinite(p->loss_aware.margin)
          && p->loss_aware.margin >= 0 && p->loss_aware.margin < FS_C(1.5707963267948966)))
        return SMC_EPLAN;
    s->p = *p;
    plan_init(&s->plan, &p->plan);
    s->alpha1 = fs_pow(g->wn, 2);
    s->alpha2 = 2 * g->xi * g->wn;
    s->torques_constant = torque_model_constant(&p->torques);
    s->loss_aware = p->loss_aware.rho_hold > 0;
    s->hold = g->hold_damping > 0;
    s->hold_torques = s->hold && !(s->torques_constant && p->torques.load == 0);
    if (g->hold_damping > 0) {  // rho2 > 0 (plan_valid); Km rho2 may still underflow, the gain and rate overflow
        if (!(p->motor.Km * p->plan.rho2 > 0))
            return SMC_EGAINS;
        s->hold_gain = 2 * g->hold_damping * fs_sqrt(p->motor.J * p->motor.Nr / (p->motor.Km * p->plan.rho2));
        fs_sincos(p->motor.Nr * p->plan.theta2, &s->hold_s2, &s->hold_c2);
        s->hold_lambda = g->W1 / g->eps1;
        if (!(fs_isfinite(s->hold_gain) && fs_isfinite(s->hold_lambda)))
            return SMC_EGAINS;
    }
    // v_limit^2 less a margin of 16 rounding units (v0^2 + v1^2 is within 2 of |v|^2), capped below overflow.
    s->v_limit2_below =
        p->v_limit < fs_sqrt(FS_REAL_MAX) ? p->v_limit * p->v_limit * (1 - 16 * FS_REAL_EPSILON) : FS_REAL_MAX;
    smc_reset(s);
    return SMC_PARAMS_OK;
}

// Returns nothing; clears the accumulated status of a controller set up by smc_init.
void smc_reset(struct smc *s)
{
    s->status_seen = SMC_OK;
}

// Returns the known torque E (torque_model_torque; the constant load without the call when that is all it is).
SMC_INLINE fs_real smc_torque(const struct smc *s, fs_real t, fs_real theta, fs_real omega)
{
    return s->torques_constant ? s->p.torques.load : torque_model_torque(&s->p.torques, s->p.motor.Nr, t, theta, omega);
}

// Returns x clipped to [-1, 1] (x finite).
SMC_INLINE fs_real smc_clip1(fs_real x)
{
    return x > 1 ? 1 : x < -1 ? -1 : x;
}

// Returns nothing; writes the detent hold's voltages (smc.h) at time t for y = (ia, ib, omega, theta) with sN, cN
// the sine and cosine of Nr theta.
SMC_INLINE void smc_hold(const struct smc *s, fs_real t, const fs_real y[5], fs_real sN, fs_real cN, fs_real v[2])
{
    const struct motor_params *m = &s->p.motor;
    fs_real rho2 = s->p.plan.rho2, sp = smc_clip1(-s->hold_gain * y[2]), cp, s2 = s->hold_s2, c2 = s->hold_c2, sl, cl,
            ia, ib, emf;
    cp = fs_sqrt(1 - sp * sp);  // a NaN cannot reach here: the inputs were checked finite
    if (s->hold_torques) {      // the load angle of the known torque on theta2 at rest (no Coulomb term at rest)
        sl = smc_clip1(smc_torque(s, t, s->p.plan.theta2, 0) / (m->Km * rho2));
        cl = fs_sqrt(1 - sl * sl);
        s2 = s->hold_s2 * cl + s->hold_c2 * sl;
        c2 = s->hold_c2 * cl - s->hold_s2 * sl;
    }
    ia = rho2 * (c2 * cp - s2 * sp);
    ib = rho2 * (s2 * cp + c2 * sp);
    emf = m->Km * y[2];
    v[0] = m->R * ia + m->L * s->hold_lambda * (ia - y[0]) - emf * sN;
    v[1] = m->R * ib + m->L * s->hold_lambda * (ib - y[1]) + emf * cN;
}

// Returns E' (torque_model_rate; 0 without the call when the known torque is constant).
SMC_INLINE fs_real smc_torque_rate(const struct smc *s, fs_real t, fs_real theta, fs_real omega, fs_real acc)
{
    return s->torques_constant ? 0 : torque_model_rate(&s->p.torques, s->p.motor.Nr, t, theta, omega, acc);
}

// Returns theta'': y[4] measured, or the model's under the known torque E in motor_acceleration's operation order.
SMC_INLINE fs_real smc_acceleration(const struct smc *s, const fs_real y[5], fs_real sN, fs_real cN, fs_real E)
{
    const struct motor_params *m = &s->p.motor;
    return s->p.measurement == SMC_IDEAL ? y[4] : (m->Km * (y[1] * cN - y[0] * sN) - m->B * y[2] - E) / m->J;
}

// Returns nothing; replaces rho and rho' of the flag ref at time t by the loss-aware rho*(t) (smc.h).
static void smc_loss_aware_rho(const struct smc *s, fs_real t, fs_real ref[PLAN_FLAG_LEN])
{
    const struct motor_params *m = &s->p.motor;
    fs_real th = ref[PLAN_THETA], w = ref[PLAN_DTHETA], a = ref[PLAN_DDTHETA], A, dA, c, h = s->p.loss_aware.rho_hold;
    A = m->J * a + m->B * w + smc_torque(s, t, th, w);
    dA = m->J * ref[PLAN_DDDTHETA] + m->B * a + smc_torque_rate(s, t, th, w, a);
    c = m->Km * fs_cos(s->p.loss_aware.margin);
    ref[PLAN_RHO] = fs_sqrt(h * h + (A / c) * (A / c));
    ref[PLAN_DRHO] = A * dA / (c * c) / ref[PLAN_RHO];
}

// Returns the status bits of the unguarded law; writes its voltages (0 V on a fault) and, when w is not NULL,
// its intermediate values (nr_trig: NULL, or the caller's sin and cos of Nr theta).
SMC_INLINE uint32_t smc_law(const struct smc *s, fs_real t, const fs_real y[5], const fs_real *nr_trig, fs_real v[2],
                            struct smc_terms *w)
{
    const struct motor_params *m = &s->p.motor;
    const struct smc_gains *g = &s->p.gains;
    fs_real own[PLAN_FLAG_LEN], *ref = w ? w->flag : own, rho, sN, cN, acc, e, de, dde, s1, s2, gamma1, gamma2, E, dE_J;
    struct flat_angles a;
    int flat;
    plan_flag(&s->plan, t, ref);
    if (s->loss_aware)
        smc_loss_aware_rho(s, t, ref);
    if (w)
        w->have = SMC_HAVE_FLAG;
    // rho = hypot(ia, ib); the square root of the sum of squares is as accurate unless it over- or underflows.
    rho = y[0] * y[0] + y[1] * y[1];
    rho = rho > RHO2_SAFE_MIN && rho < RHO2_SAFE_MAX ? fs_sqrt(rho) : fs_hypot(y[0], y[1]);
    if (!(rho >= s->p.rho_min))
        return SMC_RHO;
    // phi = atan2(ia, ib) by its sine and cosine; delta = Nr theta + phi by the angle-addition formulas.
    a.sphi = y[0] / rho;
    a.cphi = y[1] / rho;
    if (nr_trig) {
        sN = nr_trig[0];
        cN = nr_trig[1];
    } else {
        fs_sincos(m->Nr * y[3], &sN, &cN);
    }
    a.sdelta = sN * a.cphi + cN * a.sphi;
    a.cdelta = cN * a.cphi - sN * a.sphi;
    // theta'' measured or the model's (smc_acceleration) under the known torques E; E' / J joins the jerk's torque
    // below (0 without the model's calls when E is the constant load).
    if (s->torques_constant) {
        E = s->p.torques.load;
        acc = smc_acceleration(s, y, sN, cN, E);
        dE_J = 0;
    } else {
        E = torque_model_torque(&s->p.torques, m->Nr, t, y[3], y[2]);
        acc = smc_acceleration(s, y, sN, cN, E);
        dE_J = torque_model_rate(&s->p.torques, m->Nr, t, y[3], y[2], acc) / m->J;
    }
    e = y[3] - ref[PLAN_THETA];
    de = y[2] - ref[PLAN_DTHETA];
    dde = acc - ref[PLAN_DDTHETA];
    s1 = rho - ref[PLAN_RHO];
    s2 = dde + s->alpha2 * de + s->alpha1 * e;
    if (s->hold && t >= s->p.plan.tf) {
        flat = FLAT_OK;
        smc_hold(s, t, y, sN, cN, v);
    } else {
        gamma1 = ref[PLAN_DRHO] - g->W1 * s1 / (fs_fabs(s1) + g->eps1);
        gamma2 = ref[PLAN_DDDTHETA] - s->alpha2 * dde - s->alpha1 * de - g->W2 * s2 / (fs_fabs(s2) + g->eps2);
        // The known torques: A = J theta'' + B theta' + E, and E' joins the jerk's torque as gamma2 + E' / J.
        gamma2 = gamma2 + dE_J;
        flat = flat_voltages_trig(m, rho, gamma1, y[2], acc, gamma2, &a, m->J * acc + m->B * y[2] + E, v);
    }
    if (w) {
        w->rho = rho;
        w->sphi = a.sphi;
        w->cphi = a.cphi;
        w->snr = sN;
        w->cnr = cN;
        w->acc = acc;
        w->s1 = s1;
        w->s2 = s2;
        w->have |= SMC_HAVE_LAW;
    }
    if (flat & FLAT_ERHO)
        return SMC_RHO;
    if (flat & FLAT_ESQRT)
        return SMC_SQRT;
    return SMC_OK;
}

// Returns the status bits of one guarded step (smc_step's contract); w and nr_trig as in smc_law.
SMC_INLINE uint32_t smc_guarded(struct smc *s, fs_real t, const fs_real y[5], const fs_real *nr_trig, fs_real v[2],
                                struct smc_terms *w)
{
    // Law (12)-(14): s1 = rho - rho*, s2 = e'' + a2 e' + a1 e; Gamma1 = rho*' - W1 s1/(|s1| + eps1),
    // Gamma2 = theta*''' - a2 e'' - a1 e' - W2 s2/(|s2| + eps2); v = flat inverse (13) with rho' -> Gamma1,
    // theta''' -> Gamma2 at the measured (rho, phi, theta, theta', theta'').
    uint32_t status;
    fs_real norm, big, z;
    v[0] = v[1] = 0;
    // x - x is 0 for a finite x and NaN for an infinite or NaN one: one test covers every input used.
    z = (t - t) + (y[0] - y[0]) + (y[1] - y[1]) + (y[2] - y[2]) + (y[3] - y[3]);
    if (s->p.measurement == SMC_IDEAL)
        z += y[4] - y[4];
    status = z == 0 ? smc_law(s, t, y, nr_trig, v, w) : SMC_NONFINITE;
    // (v0 - v0) + (v1 - v1) is 0 when both are finite and NaN otherwise, as for the inputs.
    if (status == SMC_OK && !((v[0] - v[0]) + (v[1] - v[1]) == 0))
        status = SMC_OVERFLOW;
    if (status != SMC_OK) {
        v[0] = v[1] = 0;
    } else if (v[0] * v[0] + v[1] * v[1] > s->v_limit2_below) {
        // Near or over the limit (or the squares overflowed): decide on hypot, as the contract states.
        if (fs_hypot(v[0], v[1]) > s->p.v_limit) {
            // Scale by the larger component first so that hypot cannot overflow; big > v_limit / 2 > 0.
            big = fs_fabs(v[0]) > fs_fabs(v[1]) ? fs_fabs(v[0]) : fs_fabs(v[1]);
            v[0] /= big;
            v[1] /= big;
            norm = fs_hypot(v[0], v[1]);
            v[0] *= s->p.v_limit / norm;
            v[1] *= s->p.v_limit / norm;
            status = SMC_SATURATED;
        }
    }
    s->status_seen |= status;
    return status;
}

// Returns the smc_status bits of this step; writes finite phase voltages v with hypot(v) <= v_limit for any
// time t and measurement y = (ia, ib, omega, theta, theta'') (y[4] read in SMC_IDEAL mode only).
uint32_t smc_step(struct smc *s, fs_real t, const fs_real y[5], fs_real v[2])
{
    return smc_guarded(s, t, y, NULL, v, NULL);
}

// Returns smc_step's status and writes its voltages v, bit for bit; also writes the step's intermediate values
// into w (w->have says which). nr_trig: NULL, or sin and cos of Nr y[3] already computed by the caller (the
// controller's Nr), which the step then uses instead of computing them.
uint32_t smc_step_terms(struct smc *s, fs_real t, const fs_real y[5], const fs_real *nr_trig, fs_real v[2],
                        struct smc_terms *w)
{
    w->have = 0;
    return smc_guarded(s, t, y, nr_trig, v, w);
}

// Returns smc_step's status; the interface's step on a struct smc.
static uint32_t smc_step_bound(void *self, fs_real t, const fs_real *y, fs_real *v)
{
    return smc_step(self, t, y, v);
}

// Returns nothing; the interface's reset on a struct smc.
static void smc_reset_bound(void *self)
{
    smc_reset(self);
}

// Returns nothing; binds s into the run loops' interface (a stateless law: the continuous loop may run it).
void smc_controller(struct smc *s, struct controller *c)
{
    c->self = s;
    c->step = smc_step_bound;
    c->reset = smc_reset_bound;
    c->stateless = true;
}
