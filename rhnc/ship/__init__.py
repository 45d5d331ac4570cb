"""The ship: its equations of motion, particulars, energy and emission rates, manoeuvre figures and model identification."""
