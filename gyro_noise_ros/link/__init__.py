"""
Portenta H7 + LSM6DSO32 link: wire protocol, decoder, datasheet scaling, device clock, SD logs, board model.

Pure Python on numpy (no ROS). The wire contract is ``docs/portenta_link.md``.

- :mod:`.protocol`: frames, :class:`~.protocol.Decoder` (never raises), counters.
- :mod:`.lsm6dso32`: full scales, ODRs, raw words to SI.
- :mod:`.clock`: uint32 unwrapping and the device-to-host time estimator.
- :mod:`.sdlog`: SD-card log files (writer, streaming reader).
- :mod:`.emulator`: the board model used by ``portenta_emulator`` and the tests.
"""
