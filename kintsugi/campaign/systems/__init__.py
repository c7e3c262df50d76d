"""Each built-in system's own tables, built from its methods' figures (`PegFigures`, `RunFigures`,
`CoralFigures`): `peg` (System A's Tables II and III), `tabletop` (System B's Table I), `contact` (System C's
Table I). `kintsugi.campaign.tables` imports one when a campaign of that system is tabulated; a plugin's system
registers its own with `register_tables`.
"""
