"""Encounters: COLREG classification and judgement, separation figures, traffic participants and situation suites."""
