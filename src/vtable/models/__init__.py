"""The models a `Physics` is realised in: the reduced model the diagnosis fits
(`reduced.ReducedModel`, built by `reduced.ReducedAssembly`) and the multibody virtual table
(`virtual.VirtualAssembly`, stepped by `vtable.sim.simulate`). Both speak the assembly
vocabulary of `vtable.effects.base.Assembly`, so every effect enters both; effects sit below
this package and never import it."""
