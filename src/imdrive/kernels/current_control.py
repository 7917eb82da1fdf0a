"""The synchronous-frame current controllers' feed-forward (``control.current_controller``).

The stator current in the controller's frame obeys

    sigma_L1 di/dt = v - R_sigma i - j w_e sigma_L1 i - e_r,    e_r ~ j w_e (M/L2) psi

and :func:`imdrive.kernels.ifoc.foc_step` applies ``v = kp e + ki int e + ff`` (``e = i* - i``).

* ``"pi"`` (the default up to the rated speed): ``ff = j w_e (sigma_L1 i* + (M/L2) psi_hat)``,
  the cross-coupling taken at the references, with ``kp = a_c sigma_L1``,
  ``ki = a_c R_sigma`` (the PI's zero cancels the pole ``R_sigma/sigma_L1``). The
  cross-coupling of the current error, ``j w_e sigma_L1 e``, is left to the PI, and a back-emf
  error (the rotor flux off the controller's model ``psi_hat``) is rejected only at the
  cancelled open-loop pole ``R_sigma/sigma_L1`` (306 rad/s on Table IV, a quarter of the
  200 Hz loop's ``a_c``).
* ``"imc"`` (internal model control: Harnefors and Nee, IEEE Trans. Ind. Appl. 34(1), 1998):
  ``ff = j w_e (sigma_L1 i + (M/L2) psi_hat) - R_a i``, the cross-coupling taken at the
  measured current and an active resistance ``R_a = a_c sigma_L1 - R_sigma``, with
  ``ki = a_c (R_sigma + R_a)``. The plant the PI sees is then ``1/(sigma_L1 s + R_sigma +
  R_a)``, pole at ``a_c``: the reference loop is still ``a_c/(s + a_c)`` and a back-emf error
  is rejected at ``a_c`` too, whatever ``w_e``.

In deep field weakening the back-emf is nearly all of the voltage (0.9 of the limit) and
``w_e sigma_L1`` 0.58 of ``kp`` (twice the rated speed of Table IV): with ``"pi"``, regenerating
at the available torque, the rotor flux's swings left current errors of 0.2-0.3 A that
turned the indirect orientation, a 6-10 Hz oscillation of flux and frame grew until the
voltage limit, where the d axis's priority took the back-emf's voltage and the frame settled
82 degrees off the flux with the voltage at the limit (even with the measured speed and the
exact R2). With ``"imc"`` the same run holds the frame within 0.1 degree.
"""

from __future__ import annotations

from imdrive.kernels.jit import njit


@njit(cache=True)
def decoupling_voltage(p, w_e, sigma_L1, e_psi, id_ref, iq_ref, i_d, i_q):
    """The current PIs' feed-forward ``(ff_d, ff_q)``, V (module docstring).

    Parameters
    ----------
    p : CONTROL_PARAMS record
        ``decouple`` (feed-forward on), ``dec_meas`` (cross-coupling at the measured current)
        and ``R_a`` (active resistance, V/A; 0: none).
    w_e : float
        The controller's synchronous speed, rad/s.
    sigma_L1 : float
        The controller's transient inductance, H.
    e_psi : float
        ``(M/L2) psi_hat``, the model's rotor flux seen from the stator, Wb.
    id_ref, iq_ref : float
        Current references, A.
    i_d, i_q : float
        Measured current in the controller's frame, A.

    Returns
    -------
    ff_d, ff_q : float
    """
    ff_d = 0.0
    ff_q = 0.0
    if p.decouple:
        if p.dec_meas:
            ff_d = -w_e * sigma_L1 * i_q
            ff_q = w_e * (sigma_L1 * i_d + e_psi)
        else:
            ff_d = -w_e * sigma_L1 * iq_ref
            ff_q = w_e * (sigma_L1 * id_ref + e_psi)
    if p.R_a != 0.0:
        ff_d -= p.R_a * i_d
        ff_q -= p.R_a * i_q
    return ff_d, ff_q
