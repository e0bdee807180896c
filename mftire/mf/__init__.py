"""Magic Formula 6.1/6.2 steady-state equations, split by channel.

The C model is ``c/`` (``mf_eval.c`` the equations, ``mf_kernel.c`` the array kernel, ``mf_transient.c``
the transient tyre).

Module map (Pacejka 2012, 3rd ed., §4.3.2 and Appendix 3; Besselink, Schmeitz and
Pacejka 2010, "An improved Magic Formula/Swift tyre model that can handle inflation
pressure changes", Vehicle System Dynamics 48:S1):

===================  ========================================================
===================  ========================================================

The reference for numerical agreement is MFeval 4.0 (M. Furlan Tassara).  Where it
departs from the book to match TNO's solver we follow it; each place says so in a
comment starting with ``MFeval departure:``.
"""
