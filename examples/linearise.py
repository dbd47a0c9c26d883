"""Linearisation of the platform through the FMU's directional derivatives: the command. The
work is in `stewart_fmu.linearise` (see its documentation).

    python examples/linearise.py [--si] [--gain G] [--damping D] [--output folder]
"""

from stewart_fmu.linearise import main

if __name__ == "__main__":
    main()
