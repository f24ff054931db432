"""frictex: render textures and objects on ultrasonic friction-modulation touchscreens.

The public, typed API. Everything else lives in the four layers below it, in the order
DESIGN.md's data flow gives: ``frictex.app`` (commands, replay engine, live demo,
reports) uses ``frictex.rendering`` (tracking, renderers, composition, friction
inversion, visual layer), which uses ``frictex.textures`` (the texture file format and
its library), which uses ``frictex.device`` (structures, actuation, link, protocol).
"""
