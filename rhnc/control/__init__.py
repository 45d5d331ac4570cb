"""Control: the NMPC with its collision and COLREG constraints, the disturbance observer, solver watchdog and allocation."""
