"""Magic Formula 6.1/6.2 steady-state equations, split by channel.

The C model is ``c/`` (``mf_eval.c`` the equations, ``mf_kernel.c`` the array kernel, ``mf_transient.c``
the transient tyre).

Module map (Pacejka 2012, 3rd ed., §4.3.2 and Appendix 3; Besselink, Schmeitz and
Pacejka 2010, "An improved Magic Formula/Swift tyre model that can handle inflation
pressure changes", Vehicle System Dynamics 48:S1):

===================  ========================================================
``modes``            the three-digit ``useMode`` of the reference evaluator
``inputs``           limit checks, low-speed reduction factors
``basic``            normalised load/pressure increments, star and prime quantities
``longitudinal``     Fx0 (pure) and Fx (combined)
``lateral``          Fy0 (pure) and Fy (combined)
``aligning``         trail, residual torque, Mz0 and Mz
``overturning``      Mx
``rolling``          My
``turnslip``         the zeta reduction factors, turn-slip spin
``vertical``         effective rolling radius, loaded radius, deflection, contact patch
``relaxation``       carcass stiffnesses and relaxation lengths
``solver``           the one pipeline (prepare, forces, outputs): the 30 output channels
``extensions``       model extensions: scaling factors as functions of a variable
``derivatives``      exact derivatives of a channel by its coefficients (reverse mode, the fit's Jacobian)
``thermal_section``  the ``[MFTIRE_THERMAL]`` section: thermal parameters, the node of each temperature law
``kernel``           the compiled array kernel (the C model over arrays, loaded with ctypes)
``_kernel_build``    how the kernel is compiled (setup.py and ``python -m mftire.mf.kernel build``)
``spec``             the contract of Python and C: outputs, groups, warnings, families, builtin variables (data)
``cheaders``         the generated C headers of the C model (``c/``): ``MFParams``, extension terms, the spec
``family``           model codes: MF 5.2 family (FITTYP 6, PAC2002), PAC2002 marker
``pac2002``          PAC2002 (Adams MF-Tyre 5.2): its differences from MF 5.2
``usedkeys``         generates :mod:`mftire.iotools.evaluator_keys` (the ``.tir`` keys read)
===================  ========================================================

The reference for numerical agreement is MFeval 4.0 (M. Furlan Tassara).  Where it
departs from the book to match TNO's solver we follow it; each place says so in a
comment starting with ``MFeval departure:``.
"""
