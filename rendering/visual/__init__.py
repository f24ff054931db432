"""The visual layer: the scene a texture file describes, drawn with moderngl.

What the eye sees and what the finger feels come from the same ``textures.model``
objects, in mm: ``scene_image`` evaluates every layer's ``mu_at``/``covers`` at the
pixel grid (supersampled, so a 0.6 mm grating on a ~7.4 px/mm screen is exact in
period and free of moire); ``overlay`` keeps what moves (finger cursors, trails, the
scope strip); ``compositor`` draws both with OpenGL into whatever ``context`` provides
(a glfw window or an offscreen EGL framebuffer, at any pixel size).
"""
