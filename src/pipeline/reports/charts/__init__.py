"""A small vector chart renderer for the reports: a figure described as data
(:mod:`.model`), laid out once into primitives in points (:mod:`.layout`, :mod:`.ticks`,
:mod:`.scene`) and written as SVG (:mod:`.svg`) or PDF path operators (:mod:`.pdf`)."""
