"""The rig: real and virtual devices, the real-time loop, the live view and LSL.

The DAQ board, the i-Limb and the Ability Hand drivers and their virtual twins
(:mod:`.devices`), the hands' registry (:mod:`.hands`), the safety loop that
runs a reflex against them (:mod:`.runtime`), the Foxglove live view
(:mod:`.live`) and Lab Streaming Layer outlets (:mod:`.lsl`). It stands on
the methods and the simulator (the simulated rig), never on the reproduction.
"""
