"""The visual layer: the scene a texture file describes, drawn with moderngl.

What the eye sees and what the finger feels come from the same ``textures.model``
objects, in mm: ``scene_image`` averages every layer over each pixel (periodic layers
exactly, from a table over one period; other boundaries by supersampling the pixels they
cross), so a 0.6 mm grating on a ~7.4 px/mm screen is exact in period and free of moire;
``overlay`` keeps what moves (finger cursors, trails, the scope strip, force arrows);
``modal_view`` the vibration amplitude of a modal device (beam, 2D plate) from the
commands sent; ``compositor`` draws all of it with OpenGL into whatever ``context``
provides (a glfw window or an offscreen EGL framebuffer, at any pixel size).
"""
