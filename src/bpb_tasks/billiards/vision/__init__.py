"""Reading a billiards scene back from what a model is given: the ``init.png`` image and the
prompt text (the ``baseline:vision`` adapter's perception).

The frame comes from the axes' ticks, every ball's centre and id from template matching against
the renderer's own ball sprites and colours, the cue velocity from the arrow's direction and the
speed printed in the header (matched against the renderer's own glyphs). Constants the image
does not show (radius, friction, pockets, horizon) are read from the prompt's words.
"""
