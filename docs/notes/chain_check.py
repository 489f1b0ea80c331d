# Own numerical check (not from any source): quasi-static uniform chain, wall spring,
# n nodes, each with dry friction alpha on the fixed support, force F on node n.
# Each load step = implicit Euler step = minimise 1/2 x'Kx - F x_n + sum alpha|x_i - x_i_prev|
# solved by exact coordinate descent (soft-thresholding).
import numpy as np
def K_of(n,k):
    K=np.zeros((n,n))
    for i in range(n):
        K[i,i]=2*k if i<n-1 else k
        if i>0: K[i,i-1]=K[i-1,i]=-k
    return K
def step(x0,F,K,alpha,sweeps=4000):
    n=len(x0); x=x0.copy(); b=np.zeros(n); b[-1]=F
    for _ in range(sweeps):
        xo=x.copy()
        for i in range(n):
            r=b[i]-K[i]@x+K[i,i]*x[i]          # force from others + load
            z=r/K[i,i]-x0[i]                   # unconstrained increment
            d=np.sign(z)*max(abs(z)-alpha/K[i,i],0.0)
            x[i]=x0[i]+d
        if np.max(abs(x-xo))<1e-13: break
    return x
n,k,alpha=6,1.0,1.0
K=K_of(n,k); x=np.zeros(n)
def xload(F):
    j=min(int(np.floor(F/alpha+1e-12)),n)
    return (j*F-alpha*j*(j+1)/2)/k, j
errs=[]
for F in np.linspace(0,8.5,171):
    x=step(x,F,K,alpha)
    xa,j=xload(F); nsl=int(np.sum(abs(x)>1e-9))
    errs.append(abs(x[-1]-xa))
    if abs(F-round(F*2)/2)<1e-9: print(f"F={F:5.2f} x_end={x[-1]:.6f} formula={xa:.6f} moved_nodes={nsl} j={j}")
print("max err loading",max(errs))
# unloading from Fmax=3.5 (j=3 < n) to -3.5, compare with Masing 2*xload(dF/2)
x=np.zeros(n)
for F in np.linspace(0,3.5,71): x=step(x,F,K,alpha)
xmax=x[-1]; e=[]
for F in np.linspace(3.5,-3.5,141):
    x=step(x,F,K,alpha)
    dF=3.5-F; xm=xmax-2*xload(dF/2)[0]; e.append(abs(x[-1]-xm))
print("xmax",xmax,"max err vs Masing on [-Fmax,Fmax]",max(e))
# continue reloading beyond -Fmax to see whether Masing still holds (expected: not in general)
for F in np.linspace(-3.5,-6,51):
    x=step(x,F,K,alpha)
dF=3.5-(-6); print("at F=-6: x=",x[-1]," Masing-extrapolated=",xmax-2*xload(dF/2)[0], " virgin-curve mirror=",-xload(6)[0])
