"""FMI co-simulation master for the RHNC toolchain: scenarios, participants, runs, batches."""

__version__ = "0.1.0"
