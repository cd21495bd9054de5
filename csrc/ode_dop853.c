// Dormand-Prince 8(5,3) (Hairer's DOP853): error estimate from the 5th- and 3rd-order embedded solutions,
// step control, FSAL, 7th-order dense output with three extra stages, and a cubic Hermite interpolant.
#include "ode.h"

// The method's published data (Hairer, Norsett & Wanner, Solving ODEs I, II.10): nodes c, matrix a (row 12:
// the 8th-order weights b; rows 13..15: the dense-output stages), error weights e5 (5th order) and bhat (3rd
// order: err3 = b - bhat), dense-output weights d.
// clang-format off: the published tables keep their packed rows
static const fs_real c_[16] = {
    0, FS_C(0.526001519587677318785587544488e-01), FS_C(0.789002279381515978178381316732e-01),
    FS_C(0.118350341907227396726757197510), FS_C(0.281649658092772603273242802490),
    FS_C(0.333333333333333333333333333333), FS_C(0.25), FS_C(0.307692307692307692307692307692),
    FS_C(0.651282051282051282051282051282), FS_C(0.6), FS_C(0.857142857142857142857142857142), FS_C(1.0),
    FS_C(1.0), FS_C(0.1), FS_C(0.2), FS_C(0.777777777777777777777777777778)
};
static const fs_real a_[16][15] = {
    {0},
    {FS_C(5.26001519587677318785587544488e-2)},
    {FS_C(1.97250569845378994544595329183e-2), FS_C(5.91751709536136983633785987549e-2)},
    {FS_C(2.95875854768068491816892993775e-2), 0, FS_C(8.87627564304205475450678981324e-2)},
    {FS_C(2.41365134159266685502369798665e-1), 0, FS_C(-8.84549479328286085344864962717e-1),
     FS_C(9.24834003261792003115737966543e-1)},
    {FS_C(3.7037037037037037037037037037e-2), 0, 0, FS_C(1.70828608729473871279604482173e-1),
     FS_C(1.25467687566822425016691814123e-1)},
    {FS_C(3.7109375e-2), 0, 0, FS_C(1.70252211019544039314978060272e-1), FS_C(6.02165389804559606850219397283e-2),
     FS_C(-1.7578125e-2)},
    {FS_C(3.70920001185047927108779319836e-2), 0, 0, FS_C(1.70383925712239993810214054705e-1),
     FS_C(1.07262030446373284651809199168e-1), FS_C(-1.53194377486244017527936158236e-2),
     FS_C(8.27378916381402288758473766002e-3)},
    {FS_C(6.24110958716075717114429577812e-1), 0, 0, FS_C(-3.36089262944694129406857109825),
     FS_C(-8.68219346841726006818189891453e-1), FS_C(2.75920996994467083049415600797e1),
     FS_C(2.01540675504778934086186788979e1), FS_C(-4.34898841810699588477366255144e1)},
    {FS_C(4.77662536438264365890433908527e-1), 0, 0, FS_C(-2.48811461997166764192642586468),
     FS_C(-5.90290826836842996371446475743e-1), FS_C(2.12300514481811942347288949897e1),
     FS_C(1.52792336328824235832596922938e1), FS_C(-3.32882109689848629194453265587e1),
     FS_C(-2.03312017085086261358222928593e-2)},
    {FS_C(-9.3714243008598732571704021658e-1), 0, 0, FS_C(5.18637242884406370830023853209),
     FS_C(1.09143734899672957818500254654), FS_C(-8.14978701074692612513997267357),
     FS_C(-1.85200656599969598641566180701e1), FS_C(2.27394870993505042818970056734e1),
     FS_C(2.49360555267965238987089396762), FS_C(-3.0467644718982195003823669022)},
    {FS_C(2.27331014751653820792359768449), 0, 0, FS_C(-1.05344954667372501984066689879e1),
     FS_C(-2.00087205822486249909675718444), FS_C(-1.79589318631187989172765950534e1),
     FS_C(2.79488845294199600508499808837e1), FS_C(-2.85899827713502369474065508674),
     FS_C(-8.87285693353062954433549289258), FS_C(1.23605671757943030647266201528e1),
     FS_C(6.43392746015763530355970484046e-1)},
    {FS_C(5.42937341165687622380535766363e-2), 0, 0, 0, 0, FS_C(4.45031289275240888144113950566),
     FS_C(1.89151789931450038304281599044), FS_C(-5.8012039600105847814672114227),
     FS_C(3.1116436695781989440891606237e-1), FS_C(-1.52160949662516078556178806805e-1),
     FS_C(2.01365400804030348374776537501e-1), FS_C(4.47106157277725905176885569043e-2)},
    {FS_C(5.61675022830479523392909219681e-2), 0, 0, 0, 0, 0, FS_C(2.53500210216624811088794765333e-1),
     FS_C(-2.46239037470802489917441475441e-1), FS_C(-1.24191423263816360469010140626e-1),
     FS_C(1.5329179827876569731206322685e-1), FS_C(8.20105229563468988491666602057e-3),
     FS_C(7.56789766054569976138603589584e-3), FS_C(-8.298e-3)},
    {FS_C(3.18346481635021405060768473261e-2), 0, 0, 0, 0, FS_C(2.83009096723667755288322961402e-2),
     FS_C(5.35419883074385676223797384372e-2), FS_C(-5.49237485713909884646569340306e-2), 0, 0,
     FS_C(-1.08347328697249322858509316994e-4), FS_C(3.82571090835658412954920192323e-4),
     FS_C(-3.40465008687404560802977114492e-4), FS_C(1.41312443674632500278074618366e-1)},
    {FS_C(-4.28896301583791923408573538692e-1), 0, 0, 0, 0, FS_C(-4.69762141536116384314449447206),
     FS_C(7.68342119606259904184240953878), FS_C(4.06898981839711007970213554331),
     FS_C(3.56727187455281109270669543021e-1), 0, 0, 0, FS_C(-1.39902416515901462129418009734e-3),
     FS_C(2.9475147891527723389556272149), FS_C(-9.15095847217987001081870187138)},
};
static const fs_real e5_[12] = {
    FS_C(0.1312004499419488073250102996e-1), 0, 0, 0, 0, FS_C(-0.1225156446376204440720569753e+1),
    FS_C(-0.4957589496572501915214079952), FS_C(0.1664377182454986536961530415e+1),
    FS_C(-0.3503288487499736816886487290), FS_C(0.3341791187130174790297318841),
    FS_C(0.8192320648511571246570742613e-1), FS_C(-0.2235530786388629525884427845e-1)
};
static const fs_real bhat_[12] = {
    FS_C(0.244094488188976377952755905512), 0, 0, 0, 0, 0, 0, 0, FS_C(0.733846688281611857341361741547), 0, 0,
    FS_C(0.220588235294117647058823529412e-1)
};
static const fs_real d_[4][16] = {
    {FS_C(-0.84289382761090128651353491142e+1), 0, 0, 0, 0, FS_C(0.56671495351937776962531783590),
     FS_C(-0.30689499459498916912797304727e+1), FS_C(0.23846676565120698287728149680e+1),
     FS_C(0.21170345824450282767155149946e+1), FS_C(-0.87139158377797299206789907490),
     FS_C(0.22404374302607882758541771650e+1), FS_C(0.63157877876946881815570249290),
     FS_C(-0.88990336451333310820698117400e-1), FS_C(0.18148505520854727256656404962e+2),
     FS_C(-0.91946323924783554000451984436e+1), FS_C(-0.44360363875948939664310572000e+1)},
    {FS_C(0.10427508642579134603413151009e+2), 0, 0, 0, 0, FS_C(0.24228349177525818288430175319e+3),
     FS_C(0.16520045171727028198505394887e+3), FS_C(-0.37454675472269020279518312152e+3),
     FS_C(-0.22113666853125306036270938578e+2), FS_C(0.77334326684722638389603898808e+1),
     FS_C(-0.30674084731089398182061213626e+2), FS_C(-0.93321305264302278729567221706e+1),
     FS_C(0.15697238121770843886131091075e+2), FS_C(-0.31139403219565177677282850411e+2),
     FS_C(-0.93529243588444783865713862664e+1), FS_C(0.35816841486394083752465898540e+2)},
    {FS_C(0.19985053242002433820987653617e+2), 0, 0, 0, 0, FS_C(-0.38703730874935176555105901742e+3),
     FS_C(-0.18917813819516756882830838328e+3), FS_C(0.52780815920542364900561016686e+3),
     FS_C(-0.11573902539959630126141871134e+2), FS_C(0.68812326946963000169666922661e+1),
     FS_C(-0.10006050966910838403183860980e+1), FS_C(0.77771377980534432092869265740),
     FS_C(-0.27782057523535084065932004339e+1), FS_C(-0.60196695231264120758267380846e+2),
     FS_C(0.84320405506677161018159903784e+2), FS_C(0.11992291136182789328035130030e+2)},
    {FS_C(-0.25693933462703749003312586129e+2), 0, 0, 0, 0, FS_C(-0.15418974869023643374053993627e+3),
     FS_C(-0.23152937917604549567536039109e+3), FS_C(0.35763911791061412378285349910e+3),
     FS_C(0.93405324183624310003907691704e+2), FS_C(-0.37458323136451633156875139351e+2),
     FS_C(0.10409964950896230045147246184e+3), FS_C(0.29840293426660503123344363579e+2),
     FS_C(-0.43533456590011143754432175058e+2), FS_C(0.96324553959188282948394950600e+2),
     FS_C(-0.39177261675615439165231486172e+2), FS_C(-0.14972683625798562581422125276e+3)},
};
// clang-format on

// Step-size control of the DOP853 code: safety factor, step ratio bounds (beta = 0: no PI term).
#define SAFE FS_C(0.9)
#define FAC_MIN FS_C(0.333)
#define FAC_MAX FS_C(6.0)
#define EPS_T FS_C(1e-14)

// Returns f's result, counting the evaluation.
static int eval(struct ode_dop853 *s, fs_real t, const fs_real *x, fs_real *dx)
{
    s->rhs_evals++;
    return s->f(s->ctx, t, x, dx);
}

// Returns nothing; writes x_old + h sum_j a[row][j] k[j] over j < n_stages into xs.
static void stage_state(const struct ode_dop853 *s, const fs_real *x_old, fs_real h, int row, int n_stages, fs_real *xs)
{
    size_t i;
    int j;
    for (i = 0; i < s->n; i++) {
        fs_real sum = 0;
        for (j = 0; j < n_stages; j++)
            sum += a_[row][j] * s->k[j][i];
        xs[i] = x_old[i] + h * sum;
    }
}

// Returns ODE_OK, ODE_EARGS for bad parameters or dimension, ODE_ERHS when f fails at (t, x), or ODE_EHMIN when
// the first step size underflows to 0; starts a DOP853 integration at (t, x) and picks the first step size.
int ode_dop853_init(struct ode_dop853 *s, const struct ode_params *p, size_t n, ode_rhs_fn f, void *ctx, fs_real t,
                    const fs_real *x)
{
    size_t i;
    int j;
    if (ode_check_args(p, n, t) != ODE_OK)
        return ODE_EARGS;
    s->p = *p;
    s->f = f;
    s->ctx = ctx;
    s->n = n;
    s->t = s->t_old = t;
    s->steps = s->rejected = s->rhs_evals = 0;
    // Before the first step the dense output is the start state.
    s->dense_ready = true;
    for (i = 0; i < n; i++) {
        s->x[i] = s->rcont[0][i] = x[i];
        for (j = 1; j < 8; j++)
            s->rcont[j][i] = 0;
    }
    // k[12] holds f(t, x) between steps (first same as last).
    if (eval(s, t, s->x, s->k[12]))
        return ODE_ERHS;
    s->rhs_evals++;
    s->h = ode_first_step(p, n, f, ctx, t, s->x, s->k[12], 8);
    return s->h > 0 ? ODE_OK : (s->h < 0 ? ODE_ERHS : ODE_EHMIN);
}

// Returns the error norm of a trial step from x to xn (stages k[0..11]), or -1 when it is not finite: the
// 5th-order estimate scaled by its ratio to the 3rd-order one, as in the DOP853 code.
static fs_real trial_error(const struct ode_dop853 *s, const fs_real *xn, fs_real h)
{
    fs_real err5 = 0, err3 = 0, sk, e5, e3, deno, err;
    size_t i;
    int j;
    for (i = 0; i < s->n; i++) {
        e5 = e3 = 0;
        for (j = 0; j < 12; j++) {
            e5 += e5_[j] * s->k[j][i];
            e3 += (a_[12][j] - bhat_[j]) * s->k[j][i];
        }
        sk = s->p.atol + s->p.rtol * fs_max(fs_fabs(s->x[i]), fs_fabs(xn[i]));
        err5 += (e5 / sk) * (e5 / sk);
        err3 += (e3 / sk) * (e3 / sk);
    }
    deno = err5 + FS_C(0.01) * err3;
    err = fs_fabs(h) * err5 / fs_sqrt((fs_real)s->n * (deno > 0 ? deno : 1));
    return fs_isfinite(err) ? err : -1;
}

// Returns 0, or nonzero when f failed; computes stages 2..12 of a step h from (t, x) and its 8th-order
// solution xn.
static int trial_step(struct ode_dop853 *s, fs_real h, fs_real *xn)
{
    fs_real xs[ODE_MAX_DIM];
    size_t i;
    int j;
    for (i = 0; i < s->n; i++)
        s->k[0][i] = s->k[12][i];
    for (j = 1; j < 12; j++) {
        stage_state(s, s->x, h, j, j, xs);
        if (eval(s, s->t + c_[j] * h, xs, s->k[j]))
            return 1;
    }
    stage_state(s, s->x, h, 12, 12, xn);
    return 0;
}

// Returns ODE_OK after one accepted step that ends at t_end at the latest (exactly at t_end when it reaches
// it), ODE_EHMIN when the step size falls below rounding level, ODE_ERHS when f keeps failing.
int ode_dop853_step(struct ode_dop853 *s, fs_real t_end)
{
    fs_real xn[ODE_MAX_DIM], fn[ODE_MAX_DIM], h, err, fac11, fac, t_new;
    bool rejected = false, last, failed;
    size_t i;
    for (;;) {
        h = fs_min(s->h, s->p.h_max);
        last = s->t + FS_C(1.01) * h >= t_end;
        if (last)
            h = t_end - s->t;
        if (!(h > EPS_T * fs_max(fs_fabs(s->t), 1)))
            return last && h == 0 ? ODE_OK : ODE_EHMIN;
        t_new = last ? t_end : s->t + h;
        failed = trial_step(s, h, xn) != 0;
        err = failed ? -1 : trial_error(s, xn, h);
        // The slope at the new point is the next step's first stage; a failure there rejects the step too.
        if (err >= 0 && err <= 1 && eval(s, t_new, xn, fn)) {
            failed = true;
            err = -1;
        }
        fac11 = err > 0 ? fs_sqrt(fs_sqrt(fs_sqrt(err))) : 0;  // err^(1/8)
        if (err < 0 || err > 1) {
            // Reject: shrink by the error estimate, or tenfold when f failed or the trial was not finite.
            s->h = err < 0 ? h * FS_C(0.1) : h / fs_min(1 / FAC_MIN, fac11 / SAFE);
            s->rejected++;
            rejected = true;
            if (failed && !(s->h > EPS_T * fs_max(fs_fabs(s->t), 1)))
                return ODE_ERHS;
            continue;
        }
        fac = fs_max(1 / FAC_MAX, fs_min(1 / FAC_MIN, fac11 / SAFE));
        // The cubic Hermite part of the dense output (end states and slopes); d's part waits for a request.
        for (i = 0; i < s->n; i++) {
            s->rcont[0][i] = s->x[i];
            s->rcont[1][i] = xn[i] - s->x[i];
            s->rcont[2][i] = h * s->k[0][i] - s->rcont[1][i];
            s->rcont[3][i] = s->rcont[1][i] - h * fn[i] - s->rcont[2][i];
            s->x[i] = xn[i];
            s->k[12][i] = fn[i];
        }
        s->dense_ready = false;
        s->t_old = s->t;
        s->t = t_new;
        s->h = rejected ? fs_min(h / fac, h) : h / fac;
        s->steps++;
        return ODE_OK;
    }
}

// Returns ODE_OK, or ODE_ERHS when f fails at a dense-output stage; computes rcont[4..7] of the last step
// from its stages and three more (k[13..15]).
static int dense_stages(struct ode_dop853 *s)
{
    fs_real xs[ODE_MAX_DIM], h = s->t - s->t_old;
    size_t i;
    int j, m;
    for (j = 13; j < 16; j++) {
        stage_state(s, s->rcont[0], h, j, j, xs);
        if (eval(s, s->t_old + c_[j] * h, xs, s->k[j]))
            return ODE_ERHS;
    }
    for (m = 0; m < 4; m++)
        for (i = 0; i < s->n; i++) {
            fs_real sum = 0;
            for (j = 0; j < 16; j++)
                sum += d_[m][j] * s->k[j][i];
            s->rcont[4 + m][i] = h * sum;
        }
    s->dense_ready = true;
    return ODE_OK;
}

// Returns ODE_OK, or ODE_ERHS when f fails at a dense-output stage; writes the 7th-order dense-output state
// at t in [t_old, t] of the last step (the first call within a step evaluates three more stages).
int ode_dop853_dense(struct ode_dop853 *s, fs_real t, fs_real *x)
{
    fs_real h = s->t - s->t_old, th = h > 0 ? (t - s->t_old) / h : 1, th1 = 1 - th, par;
    size_t i;
    if (!s->dense_ready && dense_stages(s) != ODE_OK)
        return ODE_ERHS;
    for (i = 0; i < s->n; i++) {
        par = s->rcont[4][i] + th * (s->rcont[5][i] + th1 * (s->rcont[6][i] + th * s->rcont[7][i]));
        x[i] = s->rcont[0][i] + th * (s->rcont[1][i] + th1 * (s->rcont[2][i] + th * (s->rcont[3][i] + th1 * par)));
    }
    return ODE_OK;
}

// Returns nothing; writes the cubic Hermite interpolant of the last step at t in [t_old, t] (its end states
// and slopes, no evaluation of f; 4th order).
void ode_dop853_hermite(const struct ode_dop853 *s, fs_real t, fs_real *x)
{
    fs_real h = s->t - s->t_old, th = h > 0 ? (t - s->t_old) / h : 1, th1 = 1 - th;
    size_t i;
    for (i = 0; i < s->n; i++)
        x[i] = s->rcont[0][i] + th * (s->rcont[1][i] + th1 * (s->rcont[2][i] + th * s->rcont[3][i]));
}
