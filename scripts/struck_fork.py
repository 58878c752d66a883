"""Writes struck tuning-fork records as a slow-motion camera's tracker gives them (a wide CSV:
t_s and one column per tine point): 32, 64 and 128 Hz at 250, 500 and 1000 fps, 4 s, damping
drawn in 0.0002-0.002, struck before the record ("after"), during it ("strike") or twice
("twostrikes"); a hand-held camera's drift (three sines at 0.3-3 Hz) and 0.03 px of tracking
noise. Independent of our generator (plain numpy). Usage: struck_fork.py SEED OUTDIR; then
`host-harness modal --displacement OUTDIR/f32_after.csv --out M` for each file (and the same
with the first column only). docs/validation.md section 9 lists the results.
"""
import numpy as np, sys
rng=np.random.default_rng(int(sys.argv[1]))
cases=[]
for f,fs in [(32,250),(64,500),(128,1000)]:
  for kind in ['strike','after','twostrikes']:
    dur=4.0; n=int(dur*fs); t=np.arange(n)/fs
    zeta=rng.uniform(2e-4,2e-3)
    w=2*np.pi*f
    def ring(t0,a):
        tt=t-t0; y=np.where(tt>=0,a*np.exp(-zeta*w*tt)*np.sin(w*np.sqrt(1-zeta**2)*tt),0.0); return y
    if kind=='strike': y=ring(0.6,2.0)
    elif kind=='after': y=ring(-0.3,2.0)
    else: y=ring(0.5,2.0)+ring(2.2,1.5)
    # hand-held camera drift (low-frequency) and tracker noise
    drift=sum(rng.uniform(0.2,0.8)*np.sin(2*np.pi*rng.uniform(0.3,3)*t+rng.uniform(0,6)) for _ in range(3))
    y2=0.3*y  # second tine point
    cols=[y+drift+rng.normal(0,0.03,n), y2+drift+rng.normal(0,0.03,n)]
    name=f'{sys.argv[2]}/f{f}_{kind}.csv'
    with open(name,'w') as fh:
        fh.write('t_s,p1,p2\n')
        for i in range(n): fh.write(f'{t[i]:.6f},{cols[0][i]:.5f},{cols[1][i]:.5f}\n')
    print(name, f, zeta)
