"""Audio-interface output: the plate's carrier synthesised on the host and played through
PortAudio (``--device audio[:NAME]``), or written to a WAV file (``audio:wav:PATH``).

- :mod:`.options`: the ``audio`` device's ARG grammar and the drive figures it resolves
  (carrier, um per volt, voltage limit) into an :class:`~.options.AudioPlan`.
- :mod:`.synth`: sans-IO synthesis, a block of commands (um, rad) in, audio frames out,
  state carried; the exact carrier phase.
- :mod:`.ring`: the single-producer/single-consumer frame ring and the callback's body
  (starvation ramp, accounting); no PortAudio.
- :mod:`.output`: the producer's side shared by both outputs (the ``OutputDevice``
  contract of ``device.link.devices``); :mod:`.stream` plays into PortAudio
  (python-sounddevice, the ``audio`` extra), :mod:`.wav` writes the same frames to a file.
- :mod:`.open`: the ``frictex.devices`` entry point, ``open_audio(arg, request)``.
"""
